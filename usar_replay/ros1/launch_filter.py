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
from collections.abc import Iterable
from pathlib import Path
from typing import Any

__all__ = ["apply", "load_plan", "plan", "rows"]


def plan(
    replaced: dict[str, str],
    world_namespaces: Iterable[str],
    params: dict[str, Any],
    replaced_file: str = "",
) -> dict[str, Any]:
    """The plan :func:`apply` follows (JSON-ready): ``params`` as ROS names -> values."""
    return {
        "replaced": dict(sorted(replaced.items())),
        "world_namespaces": sorted(world_namespaces),
        "params": {k: params[k] for k in sorted(params)},
        "replaced_file": replaced_file,
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


def apply(config: Any, the_plan: dict[str, Any]) -> list[Any]:
    """Follow ``the_plan`` on a loaded roslaunch config (see the module doc), in place; the
    dropped nodes, in the launch file's order."""
    replaced = set(the_plan.get("replaced", {}))
    world = list(the_plan.get("world_namespaces", ()))
    usar: dict[str, Any] = dict(the_plan.get("params", {}))
    dropped = [n for n in config.nodes if n.package in replaced]
    config.nodes[:] = [n for n in config.nodes if n.package not in replaced]
    for key in list(config.params):
        if _under(key, world) or _under(key, usar) or any(_under(k, [key]) for k in usar):
            del config.params[key]
    if usar:
        from roslaunch.core import Param  # Debian's roslaunch, beside which this runs

        for key, value in usar.items():
            config.params[key] = Param(key, value)
    return dropped
