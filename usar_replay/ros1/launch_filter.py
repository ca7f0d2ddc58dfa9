"""A team's launch file as the course wrote it, with usar's stand-ins in place of what it replaces.

Why here, on roslaunch's loaded config: a team's launch file includes the course's
``multiple_robots.launch`` (Gazebo's ``empty_world.launch``, ``spawn_model``, amcl, move_base,
map_server, aruco_detect, rviz, robot_state_publisher) or starts some of those itself. usar does
their jobs, so their nodes must not start, and the team's own nodes, ``<param>`` and
``<rosparam>`` must load as written. roslaunch's own loader has already resolved everything a
filter of the XML would have to redo (``$(arg)``, ``if``/``unless``, ``<group ns>``,
``<include>`` with its args, ``<remap>``, ``$(find)``) when it hands over the config: what is
left to decide is which nodes run and which parameters win. So :func:`apply` works on that
config, just before roslaunch starts it (:mod:`.launch_output` calls it), and on the node list
that ``roslaunch --nodes`` prints (the bridge's list of nodes to wait for).

The rules (the plan, written by the bridge as JSON: :func:`plan`):

* a node of a package in ``replaced`` (:data:`.standins.REPLACED`) is dropped, and listed;
* the launch file's parameters under a world namespace (``/aruco_lookup_locations``: the course
  world's targets in ``param/aruco_lookup.yaml``) are dropped: the world being graded is the
  only one the nodes see;
* the course's lookup targets wherever else the launch file puts them take the graded world's
  values (:func:`replace_targets`): a parameter named ``.../aruco_lookup_locations/target_N``
  under any namespace (a node's private ones included; ``target_N/x`` and ``/y`` too), or one
  whose value is the course's target N (``[x, y]``, or an ``x``/``y`` pair of siblings such as
  ``target_1_x``, ``target_1_y``), becomes the world's target N, or is dropped when the world
  has no target N, as the TA's new environment files do; the team's file names never matter;
* every parameter usar sets (the world's targets and homes, ``/use_sim_time``, ``/mission/*``)
  is set by roslaunch with the launch file's own, in their place: roslaunch runs a
  ``<rosparam command="delete">`` and a node's ``clear_params`` before it sets parameters, so
  usar's values win whatever the launch file does.

This module runs in two interpreters: usar's (the bridge writes the plan; tests) and Debian's
``/usr/bin/python3`` beside roslaunch (loaded by path from :mod:`.launch_output`), so it imports
only the standard library; roslaunch's ``Param`` comes in with the config.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Iterable
from pathlib import Path
from typing import Any

__all__ = ["apply", "load_plan", "plan", "replace_targets", "rows"]

_TARGET = re.compile(r"(?:.*/)?aruco_lookup_locations/target_(\d{1,3})(/x|/y)?")
_MATCH = 1e-3
"""How close (m) a value must be to the course's target to be taken for it."""


def plan(
    replaced: dict[str, str],
    world_namespaces: Iterable[str],
    params: dict[str, Any],
    replaced_file: str = "",
    course_targets: Iterable[Iterable[float]] = (),
    facts: bool = False,
    package: str = "",
    robots: Iterable[str] = (),
) -> dict[str, Any]:
    """The plan :func:`apply` follows (JSON-ready): ``params`` as ROS names -> values;
    ``course_targets``: the course world's lookup targets (:func:`replace_targets`);
    ``facts``: the node listing prints what the launch file configures (:mod:`.launch_output`)
    on its stdout, for ``package``'s ``robots``."""
    return {
        "replaced": dict(sorted(replaced.items())),
        "world_namespaces": sorted(world_namespaces),
        "params": {k: params[k] for k in sorted(params)},
        "replaced_file": replaced_file,
        "course_targets": [[float(v) for v in t] for t in course_targets],
        "facts": facts,
        "package": package,
        "robots": list(robots),
    }


def load_plan(path: str | Path) -> dict[str, Any]:
    """A plan written by :func:`plan` (``json.dumps``) to ``path``."""
    with open(path, encoding="utf-8") as f:
        data: dict[str, Any] = json.load(f)
    return data


def _under(key: str, namespaces: Iterable[str]) -> bool:
    """``key`` is one of ``namespaces`` or inside one."""
    key = key.rstrip("/")
    return any(key == ns.rstrip("/") or key.startswith(ns.rstrip("/") + "/") for ns in namespaces)


def _node_name(node: Any) -> str:
    return (str(node.namespace or "/")).rstrip("/") + "/" + str(node.name)


def rows(nodes: Iterable[Any]) -> list[str]:
    """``name TAB package TAB type`` lines of roslaunch nodes (the run's node files)."""
    return [f"{_node_name(n)}\t{n.package}\t{n.type}\n" for n in nodes]


def _numbers(value: Any) -> list[Any] | None:
    """``value`` as a list when it starts with two numbers (x, y), else None (a ``<param>``'s
    ``value="[x, y]"`` is the text of one)."""
    if isinstance(value, str) and value.strip().startswith("[") and len(value) <= 200:
        try:
            value = json.loads(value)
        except ValueError:
            return None
    if not (isinstance(value, list | tuple) and len(value) >= 2):
        return None
    if all(isinstance(v, int | float) and not isinstance(v, bool) for v in value[:2]):
        return [float(value[0]), float(value[1]), *value[2:]]
    return None


def _is(value: Any, want: float) -> bool:
    ok = isinstance(value, int | float) and not isinstance(value, bool)
    return ok and math.isfinite(float(value)) and abs(float(value) - want) <= _MATCH


def _course_index(value: Any, course: list[list[float]]) -> int | None:
    xy = _numbers(value)
    if xy is None:
        return None
    for k, (cx, cy, *_) in enumerate(course, start=1):
        if _is(xy[0], cx) and _is(xy[1], cy):
            return k
    return None


def _xy_pairs(keys: Iterable[str]) -> list[tuple[str, str]]:
    """(x key, y key) of siblings named as a pair: ``.../x`` and ``.../y``, ``..._x`` and
    ``..._y``."""
    keys = set(keys)
    out = []
    for key in sorted(keys):
        for x_end, y_end in (("/x", "/y"), ("_x", "_y")):
            if key.endswith(x_end):
                other = key[: -len(x_end)] + y_end
                if other in keys:
                    out.append((key, other))
    return out


def replace_targets(config: Any, the_plan: dict[str, Any]) -> list[tuple[str, int, str]]:
    """The course's lookup targets in ``config.params`` outside the world namespaces replaced
    by the graded world's (see the module doc), in place: (parameter, target number, how it
    was known: ``name`` or ``value``) of each, sorted. The world's targets are the plan's
    ``/aruco_lookup_locations/target_N`` parameters."""
    usar: dict[str, Any] = dict(the_plan.get("params", {}))
    world_ns = list(the_plan.get("world_namespaces", ()))
    course = [list(t) for t in the_plan.get("course_targets", ()) if _numbers(list(t))]
    world: dict[int, list[float]] = {}
    for key, value in usar.items():
        m = _TARGET.fullmatch(key)
        xy = _numbers(value)
        if m and not m.group(2) and key.startswith("/aruco_lookup_locations/") and xy:
            world[int(m.group(1))] = xy[:2]
    found: dict[str, tuple[int, str, Any]] = {}  # key -> (target, how, new value or None)
    mine = [k for k in config.params if not _under(k, world_ns) and not _under(k, usar)]
    for key in mine:
        value = getattr(config.params[key], "value", None)
        m = _TARGET.fullmatch(key)
        if m:
            k, part = int(m.group(1)), m.group(2)
            how = "name"
        else:
            k, part, how = (_course_index(value, course) or 0), None, "value"
            if not k:
                continue
        new: Any = None
        if k in world:
            if part:
                new = world[k][0 if part == "/x" else 1]
            else:
                xy = _numbers(value)
                new = world[k] + (xy[2:] if xy else [])
                if isinstance(value, str):  # as the launch file wrote it: a text
                    new = json.dumps(new)
        found[key] = (k, how, new)
    scalars = [k for k in mine if isinstance(getattr(config.params[k], "value", None), int | float)]
    for x_key, y_key in _xy_pairs(k for k in scalars if k not in found):
        x, y = (getattr(config.params[k], "value", None) for k in (x_key, y_key))
        n = _course_index([x, y], course)
        if n:
            got = world.get(n)
            found[x_key] = (n, "value", None if got is None else got[0])
            found[y_key] = (n, "value", None if got is None else got[1])
    if found:
        from roslaunch.core import Param  # Debian's roslaunch, beside which this runs

        for key, (_k, _how, new) in found.items():
            if new is None:
                del config.params[key]
            else:
                config.params[key] = Param(key, new)
    return sorted((key, k, how) for key, (k, how, _new) in found.items())


def apply(
    config: Any, the_plan: dict[str, Any], targets: list[tuple[str, int, str]] | None = None
) -> list[Any]:
    """Follow ``the_plan`` on a loaded roslaunch config (see the module doc), in place; the
    dropped nodes, in the launch file's order. ``targets`` gets (parameter, target number,
    how) of each course target replaced, those under the world namespaces included."""
    replaced = set(the_plan.get("replaced", {}))
    world = list(the_plan.get("world_namespaces", ()))
    usar: dict[str, Any] = dict(the_plan.get("params", {}))
    dropped = [n for n in config.nodes if n.package in replaced]
    config.nodes[:] = [n for n in config.nodes if n.package not in replaced]
    elsewhere = replace_targets(config, the_plan)
    if targets is not None:
        for key in sorted(config.params):
            m = _TARGET.fullmatch(key)
            if m and _under(key, world):
                targets.append((key, int(m.group(1)), "name"))
        targets += elsewhere
    for key in list(config.params):
        if _under(key, world) or _under(key, usar) or any(_under(k, [key]) for k in usar):
            del config.params[key]
    if usar:
        from roslaunch.core import Param  # Debian's roslaunch, beside which this runs

        for key, value in usar.items():
            config.params[key] = Param(key, value)
    return dropped
