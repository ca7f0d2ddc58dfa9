"""ros1/launch_filter: the course template's launch files loaded by Debian's real roslaunch
(``roslaunch.config.load_config_default``, in Debian's ``/usr/bin/python3``), against usar's
stand-ins written as the underlay holds them; then usar's plan applied."""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path
from typing import Any

import pytest

from usar_replay.ros1 import launch_filter, launch_output
from usar_replay.ros1.building import debian, standins

TEMPLATE = Path(__file__).resolve().parents[2] / "examples" / "ros1" / "course_template"
WORLD = {"/aruco_lookup_locations/target_1": [1.1, 0.3], "/explorer/home": [-1.2, 0.6, 0.0]}

pytestmark = pytest.mark.skipif(
    not (debian.DIST_PACKAGES / "roslaunch" / "__init__.py").exists(),
    reason="Debian's roslaunch is not installed",
)

_LOAD = """
import json, sys
sys.path.insert(0, sys.argv[1])
import launch_filter, roslaunch.config
config = roslaunch.config.load_config_default([sys.argv[2]], None, verbose=False)
plan = launch_filter.load_plan(sys.argv[3])
dropped = launch_filter.apply(config, plan)
print(json.dumps({
    "nodes": launch_filter.rows(config.nodes),
    "dropped": launch_filter.rows(dropped),
    "params": {k: p.value for k, p in config.params.items()},
}))
"""


def _env(tmp_path: Path) -> dict[str, str]:
    standins.write(tmp_path / "underlay")
    return {
        "PATH": "/usr/bin:/bin",
        "HOME": str(tmp_path),
        "ROS_HOME": str(tmp_path / "ros_home"),
        "ROS_PACKAGE_PATH": f"{tmp_path / 'underlay'}:{TEMPLATE.parent}",
        **standins.COURSE_ENV,
    }


def _plan(tmp_path: Path) -> Path:
    plan = launch_filter.plan(standins.REPLACED, standins.WORLD_NAMESPACES, WORLD)
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(plan), encoding="utf-8")
    return path


def _load(tmp_path: Path, launch: str) -> dict[str, Any]:
    here = str(Path(launch_filter.__file__).parent)
    done = subprocess.run(
        [
            "/usr/bin/python3",
            "-P",
            "-c",
            _LOAD,
            here,
            str(TEMPLATE / "launch" / launch),
            str(_plan(tmp_path)),
        ],
        env=_env(tmp_path),
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    result: dict[str, Any] = json.loads(done.stdout.splitlines()[-1])
    return result


def test_the_course_launch_file_keeps_the_teams_node_and_drops_the_course_servers(
    tmp_path: Path,
) -> None:
    got = _load(tmp_path, "team.launch")
    assert got["nodes"] == ["/final_project_node\tfinal_project\tfinal_project_node\n"]
    dropped = {tuple(row.strip().split("\t")) for row in got["dropped"]}
    assert ("/gazebo", "gazebo_ros", "gzserver") in dropped  # from the stand-in empty_world
    assert ("/explorer/spawn_turtlebot", "gazebo_ros", "spawn_model") in dropped  # <group ns>
    assert ("/follower_move_base", "move_base", "move_base") in dropped  # <include> with args
    for pkg in ("aruco_detect", "map_server", "amcl", "rviz", "robot_state_publisher"):
        assert any(p == pkg for _, p, _ in dropped), pkg
    params = got["params"]
    # the world's targets, only: the team's YAML (4 wrong targets) is gone
    targets = {k: v for k, v in params.items() if k.startswith("/aruco_lookup_locations/")}
    assert targets == {"/aruco_lookup_locations/target_1": [1.1, 0.3]}
    assert params["/explorer/home"] == [-1.2, 0.6, 0.0]
    # the team's own parameters and YAMLs load as written
    assert params["/team/name"] == "group 0"
    assert params["/final_project_node/rate"] == 20.0
    assert params["/explorer_move_base/local_costmap/resolution"] == 0.05
    assert params["/explorer_move_base/global_costmap/inflation_radius"] == 1.0
    assert params["/explorer/tf_prefix"] == "explorer_tf"
    # xacro's stand-in ran (roslaunch runs a param's command while loading)
    assert '<robot name="turtlebot3_waffle">' in params["/robot_description"]


def test_usars_parameters_win_over_the_launch_files_own(tmp_path: Path) -> None:
    """A launch file that sets a world fact itself (a ``<param>``, the same key usar sets)."""
    launch = tmp_path / "own.launch"
    launch.write_text(
        '<launch><param name="/explorer/home" value="[9, 9, 0]"/>\n'
        '<param name="/aruco_lookup_locations/target_7" value="[5, 5]"/>\n'
        '<node pkg="final_project" type="final_project_node" name="n"/></launch>\n',
        encoding="utf-8",
    )
    here = str(Path(launch_filter.__file__).parent)
    done = subprocess.run(
        ["/usr/bin/python3", "-P", "-c", _LOAD, here, str(launch), str(_plan(tmp_path))],
        env=_env(tmp_path),
        capture_output=True,
        text=True,
        check=True,
    )
    params = json.loads(done.stdout.splitlines()[-1])["params"]
    assert params["/explorer/home"] == [-1.2, 0.6, 0.0]
    assert "/aruco_lookup_locations/target_7" not in params


def test_roslaunch_nodes_through_usars_wrapper_lists_only_the_teams_nodes(
    tmp_path: Path,
) -> None:
    """What the bridge waits for: ``roslaunch --nodes``, the plan followed."""
    cmd = launch_output.nodes_command("final_project", "team.launch", _plan(tmp_path))
    done = subprocess.run(
        ["bash", "-c", cmd], env=_env(tmp_path), capture_output=True, text=True, check=False
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["/final_project_node"]


def test_a_plan_is_json_and_reads_back(tmp_path: Path) -> None:
    plan = launch_filter.plan({"amcl": "x"}, ["/b", "/a"], {"/z": 1, "/a": [1.0]}, "r.tsv")
    assert list(plan["params"]) == ["/a", "/z"] and plan["world_namespaces"] == ["/a", "/b"]
    path = tmp_path / "p.json"
    path.write_text(json.dumps(plan), encoding="utf-8")
    assert launch_filter.load_plan(path) == plan
    assert os.path.basename(plan["replaced_file"]) == "r.tsv"


def test_a_launch_file_of_stand_ins_only_stops_with_one_line(tmp_path: Path) -> None:
    """The course's multiple_robots.launch alone: nothing of the team's would run; roslaunch
    stops at once with one line (the bridge shows it) instead of a graph that never starts."""
    plan = _plan(tmp_path)
    out = tmp_path / "output"
    out.mkdir()
    cmd = launch_output.launch_command(
        out, tmp_path / "nodes.tsv", "final_project", "multiple_robots.launch", plan
    )
    done = subprocess.run(
        ["bash", "-c", cmd], env=_env(tmp_path), capture_output=True, text=True, check=False
    )
    assert done.returncode == 1
    assert done.stderr.strip().splitlines()[-1] == (
        "usar: the launch file starts only nodes usar stands in for (amcl, aruco_detect, "
        "gazebo_ros, map_server, move_base, robot_state_publisher, rviz): start the team's own "
        "nodes in it"
    )
    assert not (tmp_path / "nodes.tsv").exists()


def test_the_courses_targets_are_the_worlds_wherever_the_launch_file_puts_them(
    tmp_path: Path,
) -> None:
    """Issue 43: the course's targets as a node's private parameters (the template's YAML
    under a file name of the team's), under another namespace, by value under a name of the
    team's (a list, an x/y pair) become the graded world's; a target the world lacks is gone;
    other numbers stay as they are."""
    (tmp_path / "targets.yaml").write_text(
        "aruco_lookup_locations:\n  target_1: [-1.752882, 3.246192]\n"
        "  target_2: [-2.510293, 1.125585]\n  target_3: [-0.289296, -1.28268]\n",
        encoding="utf-8",
    )
    launch = tmp_path / "team.launch"
    launch.write_text(
        "<launch>\n"
        '  <node pkg="final_project" type="final_project_node" name="explorer">\n'
        f'    <rosparam file="{tmp_path / "targets.yaml"}" command="load"/>\n'
        '    <param name="goal_2" value="[-2.510293, 1.125585, 0.5]"/>\n'
        '    <param name="spot/x" value="-1.752882"/><param name="spot/y" value="3.246192"/>\n'
        '    <param name="speed" value="-1.752882"/>\n'
        "  </node>\n"
        f'  <rosparam file="{tmp_path / "targets.yaml"}" command="load" ns="follower"/>\n'
        '  <param name="/team/t1_x" value="-1.752882"/>\n'
        '  <param name="/team/t1_y" value="3.246192"/>\n'
        '  <param name="/team/elsewhere" value="[-1.0, 3.0]"/>\n'
        "</launch>\n",
        encoding="utf-8",
    )
    world = {
        "/aruco_lookup_locations/target_1": [1.1, 0.3],
        "/aruco_lookup_locations/target_2": [0.5, -0.5],
    }
    plan = launch_filter.plan(
        standins.REPLACED, standins.WORLD_NAMESPACES, world,
        course_targets=standins.COURSE_TARGETS,
    )
    (tmp_path / "plan.json").write_text(json.dumps(plan), encoding="utf-8")
    here = str(Path(launch_filter.__file__).parent)
    done = subprocess.run(
        ["/usr/bin/python3", "-P", "-c", _LOAD, here, str(launch), str(tmp_path / "plan.json")],
        env=_env(tmp_path),
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    params = json.loads(done.stdout.splitlines()[-1])["params"]
    for ns in ("/explorer", "/follower"):
        assert params[f"{ns}/aruco_lookup_locations/target_1"] == [1.1, 0.3]
        assert params[f"{ns}/aruco_lookup_locations/target_2"] == [0.5, -0.5]
        assert f"{ns}/aruco_lookup_locations/target_3" not in params  # the world has 2
    assert params["/explorer/goal_2"] == "[0.5, -0.5, 0.5]"  # a <param>'s text, as written
    assert (params["/explorer/spot/x"], params["/explorer/spot/y"]) == (1.1, 0.3)
    assert (params["/team/t1_x"], params["/team/t1_y"]) == (1.1, 0.3)
    assert params["/explorer/speed"] == -1.752882  # a number alone is not a target
    assert params["/team/elsewhere"] == "[-1.0, 3.0]"
    assert params["/aruco_lookup_locations/target_1"] == [1.1, 0.3]


def test_replace_targets_says_what_it_replaced() -> None:
    class _Param:
        def __init__(self, key: str, value: Any) -> None:
            self.key, self.value = key, value

    import sys
    import types

    core = types.ModuleType("roslaunch.core")
    core.Param = _Param  # type: ignore[attr-defined]
    sys.modules.setdefault("roslaunch", types.ModuleType("roslaunch"))
    saved = sys.modules.get("roslaunch.core")
    sys.modules["roslaunch.core"] = core
    try:
        config = types.SimpleNamespace(
            params={
                "/n/aruco_lookup_locations/target_1": _Param("k", [-1.752882, 3.246192]),
                "/n/mine": _Param("k", [7.710214, -1.716889]),
                "/aruco_lookup_locations/target_1": _Param("k", [0.0, 0.0]),
            }
        )
        plan = launch_filter.plan(
            {}, standins.WORLD_NAMESPACES, {"/aruco_lookup_locations/target_4": [2.0, 2.0]},
            course_targets=standins.COURSE_TARGETS,
        )
        got = launch_filter.replace_targets(config, plan)
    finally:
        if saved is None:
            del sys.modules["roslaunch.core"]
        else:
            sys.modules["roslaunch.core"] = saved
    assert got == [("/n/aruco_lookup_locations/target_1", 1, "name"), ("/n/mine", 4, "value")]
    assert "/n/aruco_lookup_locations/target_1" not in config.params  # the world has no 1
    assert config.params["/n/mine"].value == [2.0, 2.0]
    assert config.params["/aruco_lookup_locations/target_1"].value == [0.0, 0.0]  # apply's job
