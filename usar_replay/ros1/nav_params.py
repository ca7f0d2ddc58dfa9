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
range is ignored for the template's, and the source says so.

Which goals have a plan (issue 51) is the global costmap's and the global planner's:
``global_costmap/footprint`` (else ``robot_radius``), ``footprint_padding``, ``inflation_radius``
(or ``inflation_layer/inflation_radius``) and the ``default_tolerance`` of the planner
``base_global_planner`` names; :func:`goal_limits` turns them into the inscribed radius and
tolerance usar's move_base refuses goals by, each unset or unusable one the course template's
(its footprint, costmap_2d's 0.01 m padding, 1.0 m, 0.0 m). Nothing else of move_base's
parameters is modelled by usar's navigator (its speeds are the TurtleBot3's, as the template's).
"""

from __future__ import annotations

import json
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
    "goal_limits",
    "goal_tolerances",
    "inscribed_radius",
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
_DEFAULT_GLOBAL_PLANNER = "navfn/NavfnROS"
TEMPLATE_FOOTPRINT = ((-0.205, -0.155), (-0.205, 0.155), (0.077, 0.155), (0.077, -0.155))
"""``footprint`` in the template's ``costmap_common_params.yaml``."""
TEMPLATE_PADDING = 0.01
"""costmap_2d's default ``footprint_padding`` (the template does not set it)."""
TEMPLATE_INFLATION = 1.0
"""``inflation_radius`` in the template's ``costmap_common_params.yaml``."""
TEMPLATE_DEFAULT_TOLERANCE = 0.0
"""The template's global planner's ``default_tolerance``."""
_COSTMAP = {
    "footprint": ("global_costmap/footprint",),
    "robot_radius": ("global_costmap/robot_radius",),
    "footprint_padding": ("global_costmap/footprint_padding",),
    "inflation_radius": (
        "global_costmap/inflation_layer/inflation_radius",
        "global_costmap/inflation_radius",
    ),
}
"""The global costmap's parameters that decide which goals have a plan, under move_base's
private namespace (a plugin's key first)."""
_MAX_FOOTPRINT = 400
"""Characters of a footprint kept (a polygon of a few dozen points)."""
_RANGES = {
    "xy_goal_tolerance": 10.0,
    "yaw_goal_tolerance": 2 * math.pi,
    "update_min_d": 10.0,
    "update_min_a": 2 * math.pi,
    "robot_radius": 10.0,
    "footprint_padding": 1.0,
    "inflation_radius": 100.0,
    "default_tolerance": 10.0,
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
            _costmap_facts(entry, params, private, sources, label)
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


def _costmap_facts(
    entry: dict[str, Any],
    params: Mapping[str, Any],
    private: str,
    sources: Mapping[str, tuple[str, str]],
    label: Any,
) -> None:
    """The global costmap's and global planner's parameters that decide which goals have a
    plan, into ``entry`` (JSON-ready; a footprint as its list of points, or its text)."""
    gp_key = f"{private}/base_global_planner"
    global_planner = str(_value(params, gp_key) or _DEFAULT_GLOBAL_PLANNER).split("/")[-1]
    entry["global_planner"] = global_planner[:40]
    keys = {name: tuple(f"{private}/{k}" for k in ks) for name, ks in _COSTMAP.items()}
    keys["default_tolerance"] = (f"{private}/{global_planner}/default_tolerance",)
    for name, candidates in keys.items():
        key = next((k for k in candidates if k in params), None)
        if key is None:
            continue
        value = _value(params, key)
        if name == "footprint":
            points = _points(value)
            value = [list(p) for p in points] if points else str(value)[:_MAX_FOOTPRINT]
        elif not isinstance(value, bool | int | float):
            value = str(value)[:40]
        entry[name] = {"key": key, "value": value, "source": _source(key, sources, label)}


def _points(value: Any) -> tuple[tuple[float, float], ...]:
    """A footprint as costmap_2d reads it (a list of [x, y], or its text), else ()."""
    if isinstance(value, str):
        if len(value) > _MAX_FOOTPRINT:
            return ()
        try:
            value = json.loads(value)
        except ValueError:
            return ()
    if not isinstance(value, list | tuple) or not 3 <= len(value) <= 64:
        return ()
    out = []
    for p in value:
        if not isinstance(p, list | tuple) or len(p) != 2:
            return ()
        if not all(isinstance(v, int | float) and not isinstance(v, bool) for v in p):
            return ()
        x, y = float(p[0]), float(p[1])
        if not (math.isfinite(x) and math.isfinite(y) and abs(x) <= 10 and abs(y) <= 10):
            return ()
        out.append((x, y))
    return tuple(out)


def inscribed_radius(points: Iterable[tuple[float, float]], padding: float = 0.0) -> float:
    """The footprint's inscribed radius as costmap_2d computes it: each point padded away from
    the axes by ``padding`` (``padFootprint``), then the least distance from the robot's
    origin to a point or an edge (``calculateMinAndMaxDistances``)."""
    pts = [
        (x + math.copysign(padding, x) * (x != 0), y + math.copysign(padding, y) * (y != 0))
        for x, y in points
    ]
    best = min(math.hypot(x, y) for x, y in pts)
    for (ax, ay), (bx, by) in zip(pts, pts[1:] + pts[:1], strict=True):
        dx, dy = bx - ax, by - ay
        n = dx * dx + dy * dy
        t = 0.0 if n == 0 else max(0.0, min(1.0, -(ax * dx + ay * dy) / n))
        best = min(best, math.hypot(ax + t * dx, ay + t * dy))
    return best


def goal_limits(facts_: Mapping[str, Any] | None, robot: str) -> tuple[float, float, float, str]:
    """``robot``'s (inscribed radius, inflation radius, default_tolerance, source) as its
    move_base's global costmap and planner would refuse goals by (the module doc): each value
    the package set and usable, else the course template's."""
    move_base = (facts_ or {}).get("move_base", {}) if isinstance(facts_, Mapping) else {}
    entry = move_base.get(robot, {}) if isinstance(move_base, Mapping) else {}
    entry = entry if isinstance(entry, Mapping) else {}
    used: list[str] = []

    def number(name: str, default: float) -> float:
        value, where = _number(entry, name)
        if value is None and _is_zero(entry, name):
            value, where = 0.0, _where(entry, name)  # 0 is a padding's or tolerance's value
        if value is None:
            return default
        used.append(f"{name} {value:g} ({where})")
        return value

    padding = number("footprint_padding", TEMPLATE_PADDING)
    got = entry.get("footprint")
    points = _points(got.get("value")) if isinstance(got, Mapping) else ()
    if points:
        inscribed = inscribed_radius(points, padding)
        used.append(f"footprint ({_where(entry, 'footprint')})")
    else:
        radius, where = _number(entry, "robot_radius")
        if radius is not None:
            inscribed = radius + padding
            used.append(f"robot_radius {radius:g} ({where})")
        else:
            inscribed = inscribed_radius(TEMPLATE_FOOTPRINT, padding)
    inflation = number("inflation_radius", TEMPLATE_INFLATION)
    tolerance = number("default_tolerance", TEMPLATE_DEFAULT_TOLERANCE)
    source = "; ".join(used) if used else "the course template's costmap and planner defaults"
    return inscribed, inflation, tolerance, source


def _where(entry: Mapping[str, Any], name: str) -> str:
    got = entry.get(name)
    return str(got.get("source", ""))[:300] if isinstance(got, Mapping) else ""


def _is_zero(entry: Mapping[str, Any], name: str) -> bool:
    got = entry.get(name)
    value = got.get("value") if isinstance(got, Mapping) else None
    return isinstance(value, int | float) and not isinstance(value, bool) and value == 0


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
