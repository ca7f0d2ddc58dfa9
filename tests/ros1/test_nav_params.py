"""ros1/nav_params: move_base's goal tolerances and amcl's thresholds as a package's launch
files set them, read from Debian's real roslaunch (the node listing usar runs before the
graph), and the precedence: the user's explicit setting, the package's, the template's."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import nav_package
import pytest

from usar_replay.ros1 import launch_filter, launch_output, nav_params
from usar_replay.ros1.building import debian, standins
from usar_replay.ros1.pacing import graph_start

ROBOTS = ("explorer", "follower")
WORLD = {"/aruco_lookup_locations/target_1": [1.1, 0.3]}


def _node(name: str, ns: str = "/", package: str = "move_base", **remaps: str) -> Any:
    return SimpleNamespace(
        name=name, namespace=ns, package=package, remap_args=list(remaps.items())
    )


def test_a_node_is_a_robots_by_its_remap_then_its_namespace_then_its_name() -> None:
    assert nav_params.robot_of(_node("mb", cmd_vel="/follower/cmd_vel"), ROBOTS, "cmd_vel") == (
        "follower"
    )
    assert nav_params.robot_of(_node("move_base", "/explorer/"), ROBOTS, "cmd_vel") == "explorer"
    assert nav_params.robot_of(_node("explorer_move_base"), ROBOTS, "cmd_vel") == "explorer"
    # a remap to the other robot's topic wins over the node's name
    node = _node("explorer_move_base", cmd_vel="/follower/cmd_vel")
    assert nav_params.robot_of(node, ROBOTS, "cmd_vel") == "follower"
    assert nav_params.robot_of(_node("move_base"), ROBOTS, "cmd_vel") is None


def _facts(xy: Any, yaw: Any = 0.17, source: str = "param/dwa.yaml (launch/mb.launch)") -> Any:
    entry = {
        "xy_goal_tolerance": {"key": "k", "value": xy, "source": source},
        "yaw_goal_tolerance": {"key": "k", "value": yaw, "source": source},
    }
    return {"move_base": {"follower": entry}}


def test_the_package_then_the_template() -> None:
    got = nav_params.goal_tolerances(_facts(0.4), ROBOTS)
    assert got == [
        ("explorer", 0.05, 0.17, "the course template's default"),
        ("follower", 0.4, 0.17, "param/dwa.yaml (launch/mb.launch)"),
    ]
    assert nav_params.goal_tolerances(None, ["follower"]) == [
        ("follower", 0.05, 0.17, "the course template's default")
    ]


def test_the_users_explicit_setting_wins_over_the_package() -> None:
    got = nav_params.goal_tolerances(_facts(0.4), ["follower"], {"xy": 0.3})
    assert got == [
        (
            "follower",
            0.3,
            0.17,
            "xy: usar's setting mission.xy_tolerance; yaw: param/dwa.yaml (launch/mb.launch)",
        )
    ]
    assert nav_params.given_in([got[0][3], "the course template's default"]) == (
        "mission.xy_tolerance",
    )
    params = {"mission.xy_tolerance": 0.3, "mission.yaw_tolerance": 0.17}
    assert nav_params.given_tolerances(params, ["mission.xy_tolerance"]) == {"xy": 0.3}
    assert nav_params.given_tolerances(params, []) == {}


@pytest.mark.parametrize(
    ("value", "why"),
    [
        ("wide", "xy_goal_tolerance 'wide' in param/dwa.yaml (launch/mb.launch) is not a number"),
        (True, "xy_goal_tolerance 'True' in param/dwa.yaml (launch/mb.launch) is not a number"),
        (-1, "xy_goal_tolerance -1 in param/dwa.yaml (launch/mb.launch) is out of range (0, 10]"),
        (float("nan"), "xy_goal_tolerance nan in param/dwa.yaml (launch/mb.launch) is out of"),
    ],
)
def test_a_value_that_is_not_a_tolerance_is_the_templates_and_said(value: Any, why: str) -> None:
    [(_robot, xy, yaw, source)] = nav_params.goal_tolerances(_facts(value), ["follower"])
    assert (xy, yaw) == (0.05, 0.17)
    assert source.startswith("xy: the course template's default (" + why), source


def test_malformed_facts_are_the_templates() -> None:
    for facts in ({"move_base": []}, {"move_base": {"follower": 3}}, [], {"amcl": "x"}):
        assert nav_params.goal_tolerances(facts, ["follower"])[0][1:3] == (0.05, 0.17)  # type: ignore[arg-type]
        assert nav_params.amcl_thresholds(facts, "follower") == (0.25, 0.2)  # type: ignore[arg-type]


pytestmark_roslaunch = pytest.mark.skipif(
    not (debian.DIST_PACKAGES / "roslaunch" / "__init__.py").exists(),
    reason="Debian's roslaunch is not installed",
)


@pytestmark_roslaunch
def test_the_node_listing_writes_what_the_launch_files_configure(tmp_path: Path) -> None:
    """The package's move_base launch (an ``<include>``, a ``<group ns>``, ``rosparam load``
    inside the nodes) as roslaunch loads it; the YAML's and launch file's names as the package
    has them."""
    pkg = nav_package.write(tmp_path / "src" / nav_package.NAME)
    standins.write(tmp_path / "underlay")
    env = {
        "PATH": "/usr/bin:/bin",
        "HOME": str(tmp_path),
        "ROS_HOME": str(tmp_path / "ros_home"),
        "ROS_PACKAGE_PATH": f"{tmp_path / 'underlay'}:{pkg.parent}",
        **standins.COURSE_ENV,
    }
    plan = launch_filter.plan(
        standins.REPLACED,
        standins.WORLD_NAMESPACES,
        WORLD,
        course_targets=standins.COURSE_TARGETS,
        facts=True,
        package=nav_package.NAME,
        robots=ROBOTS,
    )
    (tmp_path / "plan.json").write_text(json.dumps(plan), encoding="utf-8")
    cmd = launch_output.nodes_command(nav_package.NAME, "go.launch", tmp_path / "plan.json")
    done = subprocess.run(
        ["bash", "-c", cmd], env=env, capture_output=True, text=True, check=False
    )
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert [n for n in lines if n.startswith("/")] == ["/mission"]
    facts_lines = [n for n in lines if n.startswith(graph_start.FACTS_PREFIX)]
    assert len(facts_lines) == 1 and launch_output.FACTS_PREFIX == graph_start.FACTS_PREFIX
    facts = json.loads(facts_lines[0][len(graph_start.FACTS_PREFIX) :])
    assert not (tmp_path / "launch_facts.json").exists()  # nothing the graph could rewrite
    follower = facts["move_base"]["follower"]
    assert follower["node"] == "/follower_move_base" and follower["planner"] == "DWAPlannerROS"
    assert follower["xy_goal_tolerance"] == {
        "key": "/follower_move_base/DWAPlannerROS/xy_goal_tolerance",
        "value": 0.4,
        "source": "param/dwa_local_planner_params.yaml (launch/navigation.launch)",
    }
    explorer = facts["move_base"]["explorer"]
    assert explorer["planner"] == "TrajectoryPlannerROS"  # move_base's default planner
    assert explorer["yaw_goal_tolerance"]["value"] == "wide"
    assert facts["amcl"]["explorer"]["update_min_d"]["source"] == (
        "a <param> in launch/navigation.launch"
    )
    assert nav_params.amcl_thresholds(facts, "explorer") == (0.1, 0.2)
    assert nav_params.amcl_thresholds(facts, "follower") == (0.25, 0.2)
    got = nav_params.goal_tolerances(facts, ROBOTS)
    assert got[1] == (
        "follower", 0.4, 0.17, "param/dwa_local_planner_params.yaml (launch/navigation.launch)"
    )
    robot, xy, yaw, source = got[0]
    assert (robot, xy, yaw) == ("explorer", 0.1, 0.17)
    assert source == (
        "xy: param/base_local_planner_params.yaml (launch/navigation.launch); yaw: the course "
        "template's default (yaw_goal_tolerance 'wide' in param/base_local_planner_params.yaml "
        "(launch/navigation.launch) is not a number)"
    )
    # the course's targets, loaded as the node's private parameters, by name and by value
    rows = {(r["param"], r["target"], r["how"]): r["source"] for r in facts["targets"]}
    assert rows == {
        ("/mission/aruco_lookup_locations/target_1", 1, "name"): (
            "param/our_targets.yaml (launch/go.launch)"
        ),
        ("/mission/aruco_lookup_locations/target_2", 2, "name"): (
            "param/our_targets.yaml (launch/go.launch)"
        ),
        ("/mission/aruco_lookup_locations/target_3", 3, "name"): (
            "param/our_targets.yaml (launch/go.launch)"
        ),
        ("/mission/aruco_lookup_locations/target_4", 4, "name"): (
            "param/our_targets.yaml (launch/go.launch)"
        ),
        ("/mission/my_copy/t2", 2, "value"): "an inline <rosparam> (launch/go.launch)",
    }


def _costmap(**values: Any) -> Any:
    src = "param/costmap_common_params.yaml (launch/mb.launch)"
    entry = {k: {"key": k, "value": v, "source": src} for k, v in values.items()}
    return {"move_base": {"follower": entry}}


def test_goal_limits_are_the_packages_costmap_then_the_templates() -> None:
    """The template's footprint padded by costmap_2d's 0.01 m: 0.087 m; a package's footprint,
    robot_radius, padding, inflation and default_tolerance as it sets them; a value that is not
    usable is the template's."""
    template = nav_params.goal_limits(None, "follower")
    assert template[:3] == pytest.approx((0.087, 1.0, 0.0))
    assert template[3] == "the course template's costmap and planner defaults"
    assert nav_params.inscribed_radius(nav_params.TEMPLATE_FOOTPRINT) == pytest.approx(0.077)
    square = [[-0.2, -0.2], [-0.2, 0.2], [0.2, 0.2], [0.2, -0.2]]
    got = nav_params.goal_limits(
        _costmap(footprint=square, footprint_padding=0, default_tolerance=0.5), "follower"
    )
    assert got[:3] == pytest.approx((0.2, 1.0, 0.5))
    assert "footprint (param/costmap_common_params.yaml (launch/mb.launch))" in got[3]
    text = nav_params.goal_limits(_costmap(footprint=json.dumps(square)), "follower")
    assert text[0] == pytest.approx(0.21)
    radius = nav_params.goal_limits(_costmap(robot_radius=0.3, inflation_radius=0.2), "follower")
    assert radius[:2] == pytest.approx((0.31, 0.2))
    for bad in ({"footprint": "[[0, 0]]"}, {"footprint": [[1e9, 0]] * 3}, {"robot_radius": "x"},
                {"footprint": "[" * 10_000}):
        assert nav_params.goal_limits(_costmap(**bad), "follower")[0] == pytest.approx(0.087)
    for facts in ({"move_base": []}, {"move_base": {"follower": 3}}, []):
        assert nav_params.goal_limits(facts, "follower")[0] == pytest.approx(0.087)  # type: ignore[arg-type]


def test_facts_read_the_global_costmap_and_planner() -> None:
    """A move_base node's global costmap parameters and its global planner's tolerance, under
    its private namespace, as roslaunch loaded them."""
    p = "/follower_move_base"
    params = {
        f"{p}/base_global_planner": "global_planner/GlobalPlanner",
        f"{p}/GlobalPlanner/default_tolerance": 0.0,
        f"{p}/global_costmap/footprint": [[-0.205, -0.155], [-0.205, 0.155], [0.077, 0.155],
                                          [0.077, -0.155]],
        f"{p}/global_costmap/inflation_radius": 1.0,
        f"{p}/global_costmap/inflation_layer/inflation_radius": 0.5,
    }
    node = _node("follower_move_base", cmd_vel="/follower/cmd_vel")
    facts = nav_params.facts(params, [node], {}, ROBOTS)
    entry = facts["move_base"]["follower"]
    assert entry["global_planner"] == "GlobalPlanner"
    assert entry["default_tolerance"]["value"] == 0.0
    inflation_key = f"{p}/global_costmap/inflation_layer/inflation_radius"
    assert entry["inflation_radius"]["key"] == inflation_key
    assert entry["footprint"]["value"][0] == [-0.205, -0.155]
    inscribed, inflation, tolerance, _ = nav_params.goal_limits(json.loads(json.dumps(facts)),
                                                                "follower")
    assert (inscribed, inflation, tolerance) == pytest.approx((0.087, 0.5, 0.0))
