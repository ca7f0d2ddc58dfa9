"""move_base's and amcl's parameters as the package's launch files set them, per robot.

Why: usar stands in for move_base and amcl, but a package configures them: its move_base launch
loads a ``dwa_local_planner_params.yaml`` whose ``xy_goal_tolerance`` may be 0.4 (the robot
then stops up to 0.4 m short on the course), its amcl launch sets ``update_min_d``. usar's
stand-ins do as those files say (issue 43). The values are read from roslaunch's loaded config
(:func:`facts`, run beside roslaunch by :mod:`.launch_output` when it lists the nodes; only the
standard library), so every ``$(arg)``, ``<group ns>``, ``<include>`` and ``ns=`` is resolved as
on the course, never by a file's name:

* a ``move_base`` (``amcl``) node of the launch file is a robot's when it remaps ``cmd_vel``
  (``amcl_pose``) into the robot's namespace, else when its namespace, else its name, names
  the robot (the template's ``explorer_move_base``);
* its local planner is the one ``base_local_planner`` names (move_base's default
  ``base_local_planner/TrajectoryPlannerROS`` when unset), and the tolerances are that
  planner's ``xy_goal_tolerance`` and ``yaw_goal_tolerance`` under the node's private
  namespace; amcl's are ``update_min_d`` and ``update_min_a``.

Then :func:`goal_tolerances` decides (the bridge's move_base and the log's ``ros1.toml`` call
it with the same facts): a tolerance the user set explicitly (``--set mission.xy_tolerance=``
or ``--settings``) wins, then the package's, then the course template's
(``param/dwa_local_planner_params.yaml``: 0.05 m, 0.17 rad). A value that is not a number in
range is ignored for the template's, and the source says so. Nothing else of move_base's
parameters is modelled by usar's navigator (its speeds are the TurtleBot3's, as the template's).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from typing import Any

__all__ = [
    "AMCL_DEFAULTS",
    "TEMPLATE_SOURCE",
    "TEMPLATE_XY",
    "TEMPLATE_YAW",
    "amcl_thresholds",
    "facts",
    "given_in",
    "given_tolerances",
    "goal_tolerances",
    "robot_of",
]

TEMPLATE_XY = 0.05
"""``DWAPlannerROS/xy_goal_tolerance`` in the template's ``dwa_local_planner_params.yaml``."""
TEMPLATE_YAW = 0.17
"""``DWAPlannerROS/yaw_goal_tolerance`` there."""
TEMPLATE_SOURCE = "the course template's default"
AMCL_DEFAULTS = {"update_min_d": 0.25, "update_min_a": 0.2}
"""amcl's own defaults, which the template's ``explorer_amcl.launch`` also sets."""
_SETTING = "usar's setting mission.{}_tolerance"
"""The source of a tolerance the user set explicitly."""
_DEFAULT_PLANNER = "base_local_planner/TrajectoryPlannerROS"
_RANGES = {
    "xy_goal_tolerance": 10.0,
    "yaw_goal_tolerance": 2 * math.pi,
    "update_min_d": 10.0,
    "update_min_a": 2 * math.pi,
}


def _ns(node: Any) -> str:
    return "/" + "/".join(p for p in str(getattr(node, "namespace", "") or "").split("/") if p)


def robot_of(node: Any, robots: Iterable[str], topic: str) -> str | None:
    """The robot a move_base or amcl node serves (see the module doc), or None."""
    robots = list(robots)
    ns = _ns(node)
    for src, dst in list(getattr(node, "remap_args", None) or ()):
        if str(src).strip("/~").split("/")[-1] != topic:
            continue
        dst = str(dst)
        full = dst if dst.startswith("/") else f"{ns.rstrip('/')}/{dst}"
        parts = [p for p in full.split("/") if p]
        for robot in robots:
            if robot in parts[:-1]:
                return robot
    parts = [p for p in ns.split("/") if p]
    for robot in robots:
        if robot in parts:
            return robot
    name = str(getattr(node, "name", "") or "")
    for robot in robots:
        if robot in name:
            return robot
    return None


def _source(key: str, sources: Mapping[str, tuple[str, str]], label: Any) -> str:
    yaml_file, launch = sources.get(key, ("", ""))
    where = label(launch) if launch else ""
    if yaml_file:
        return f"{label(yaml_file)} ({where})" if where else label(yaml_file)
    return f"a <param> in {where}" if where else "the launch file"


def _value(params: Mapping[str, Any], key: str) -> Any:
    value = params.get(key)
    return getattr(value, "value", value)


def facts(
    params: Mapping[str, Any],
    nodes: Iterable[Any],
    sources: Mapping[str, tuple[str, str]],
    robots: Iterable[str],
    label: Any = str,
) -> dict[str, Any]:
    """What the launch file configures for usar's stand-ins, JSON-ready: ``{"move_base": {robot:
    {"node", "planner", "xy_goal_tolerance": {"key", "value", "source"}, ...}}, "amcl": {...}}``
    (``params``: roslaunch's ``config.params``; ``nodes``: the move_base and amcl nodes it
    dropped; ``label``: a file as ``usar info`` shows it)."""
    robots = list(robots)
    out: dict[str, Any] = {"move_base": {}, "amcl": {}}
    for node in nodes:
        package = str(getattr(node, "package", ""))
        if package not in ("move_base", "amcl"):
            continue
        robot = robot_of(node, robots, "cmd_vel" if package == "move_base" else "amcl_pose")
        if robot is None or robot in out[package]:
            continue  # the first node of a robot's is the one its topics reach
        private = f"{_ns(node).rstrip('/')}/{getattr(node, 'name', '')}"
        entry: dict[str, Any] = {"node": private}
        names: tuple[str, ...]
        if package == "move_base":
            planner_key = f"{private}/base_local_planner"
            planner = str(_value(params, planner_key) or _DEFAULT_PLANNER).split("/")[-1]
            entry["planner"] = planner
            base = f"{private}/{planner}"
            names = ("xy_goal_tolerance", "yaw_goal_tolerance")
        else:
            base = private
            names = tuple(AMCL_DEFAULTS)
        for name in names:
            key = f"{base}/{name}"
            if key in params:
                value = _value(params, key)
                value = value if isinstance(value, bool | int | float) else str(value)[:40]
                entry[name] = {"key": key, "value": value, "source": _source(key, sources, label)}
        out[package][robot] = entry
    return out


def _number(entry: Mapping[str, Any], name: str) -> tuple[float | None, str]:
    """(the value, '') when it is a number in range, else (None, why it was ignored)."""
    got = entry.get(name)
    if not isinstance(got, Mapping):
        return None, ""
    value = got.get("value")
    where = str(got.get("source", ""))[:300]
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None, f"{name} {str(value)[:40]!r} in {where} is not a number"
    value = float(value)
    if not (math.isfinite(value) and 0.0 < value <= _RANGES[name]):
        return None, f"{name} {value:g} in {where} is out of range (0, {_RANGES[name]:g}]"
    return value, where


def goal_tolerances(
    facts_: Mapping[str, Any] | None,
    robots: Iterable[str],
    given: Mapping[str, float] | None = None,
) -> list[tuple[str, float, float, str]]:
    """Each robot's (robot, xy, yaw, source) as usar's move_base uses them (the module doc's
    order). ``given``: the tolerances the user set explicitly, ``{"xy": 0.3}``."""
    given = dict(given or {})
    move_base = (facts_ or {}).get("move_base", {}) if isinstance(facts_, Mapping) else {}
    out = []
    for robot in robots:
        entry = move_base.get(robot, {}) if isinstance(move_base, Mapping) else {}
        entry = entry if isinstance(entry, Mapping) else {}
        picked: list[tuple[float, str]] = []
        for short, name, default in (
            ("xy", "xy_goal_tolerance", TEMPLATE_XY),
            ("yaw", "yaw_goal_tolerance", TEMPLATE_YAW),
        ):
            if short in given:
                picked.append((float(given[short]), _SETTING.format(short)))
                continue
            value, where = _number(entry, name)
            if value is not None:
                picked.append((value, where))
            else:
                why = f" ({where})" if where else ""
                picked.append((default, TEMPLATE_SOURCE + why))
        (xy, xy_src), (yaw, yaw_src) = picked
        source = xy_src if xy_src == yaw_src else f"xy: {xy_src}; yaw: {yaw_src}"
        out.append((robot, xy, yaw, source))
    return out


def amcl_thresholds(facts_: Mapping[str, Any] | None, robot: str) -> tuple[float, float]:
    """(update_min_d, update_min_a) of ``robot``'s amcl as the launch file sets them, amcl's
    defaults otherwise."""
    amcl = (facts_ or {}).get("amcl", {}) if isinstance(facts_, Mapping) else {}
    entry = amcl.get(robot, {}) if isinstance(amcl, Mapping) else {}
    entry = entry if isinstance(entry, Mapping) else {}
    got = []
    for name, default in AMCL_DEFAULTS.items():
        value, _ = _number(entry, name)
        got.append(default if value is None else value)
    return got[0], got[1]


def given_tolerances(parameters: Mapping[str, Any], given: Iterable[str]) -> dict[str, float]:
    """The tolerances the user set explicitly (``given``: the setting names of the command
    line's ``--set`` and ``--settings``), from the run's ``parameters``: ``{"xy": 0.3}``."""
    given = set(given)
    out = {}
    for short in ("xy", "yaw"):
        key = f"mission.{short}_tolerance"
        if key in given and isinstance(parameters.get(key), int | float):
            out[short] = float(parameters[key])
    return out


def given_in(sources: Iterable[str]) -> tuple[str, ...]:
    """The settings a log's goal tolerances say the user gave (``ros1.toml``'s sources), for a
    replay that decides as the recording did."""
    names = set()
    for source in sources:
        for short in ("xy", "yaw"):
            if _SETTING.format(short) in source:
                names.add(f"mission.{short}_tolerance")
    return tuple(sorted(names))
