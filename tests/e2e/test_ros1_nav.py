"""Issue 43's stand-ins as a package configures them, recorded for real (a package of Python
nodes: :mod:`nav_package`): the follower's move_base stops within the 0.4 m its own
``dwa_local_planner_params.yaml`` says, and ``usar info`` names the value and its file; a node
that loads the course's targets as its own private parameters reads the graded world's
(one-room: target_1 (1.1, 0.3), no target 2); ``/explorer/amcl_pose`` arrives at start and
after the explorer moved."""

from __future__ import annotations

import math
from pathlib import Path

import nav_package
import pytest
from clitools import usar
from conftest import one_room

from usar_replay.core import contract, msgs
from usar_replay.grading.grade import grade_file
from usar_replay.log import ros1_run
from usar_replay.log.run import open_run
from usar_replay.world.scenario_toml import save


@pytest.fixture(autouse=True, scope="module")
def _build_cache(module_build_cache: Path) -> None:
    """One build cache for this module."""


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> Path:
    tmp = tmp_path_factory.mktemp("nav")
    pkg = nav_package.write(tmp / "src" / nav_package.NAME)
    world = tmp / "room.toml"
    save(one_room(), world)
    out = tmp / "nav.mcap"
    done = usar(
        "record", "--scenario", str(world), "--ros1", str(pkg), "--launch", "go.launch",
        "--out", str(out), "--quiet",
    )
    assert done.returncode == 0, done.stdout + done.stderr
    return out


def test_the_follower_stops_within_the_packages_own_tolerance(recorded: Path) -> None:
    run = open_run(recorded)
    assert run.outcome == "done", run.outcome_reason
    facts = ros1_run.of(run)
    assert facts is not None
    assert facts.xy_goal_tolerance("follower") == 0.4
    assert facts.xy_goal_tolerance("explorer") == 0.1  # its TrajectoryPlannerROS YAML
    [reached] = [
        m.log_time_ns
        for m in run.messages([contract.goal_status("follower")])
        if isinstance(m.msg, msgs.DiagnosticStatus) and m.msg.message == "succeeded"
    ]
    poses = [
        m.msg.pose.position
        for m in run.messages([contract.truth_pose("follower")], reached)
        if isinstance(m.msg, msgs.PoseStamped)
    ]
    short = math.hypot(poses[-1].x - 0.8, poses[-1].y + 0.9)
    assert 0.25 < short <= 0.42, f"the follower stopped {short:.3f} m from its goal"


def test_info_says_the_tolerances_their_files_and_the_targets_replaced(recorded: Path) -> None:
    got = usar("info", str(recorded))
    assert got.returncode == 0, got.stderr
    flat = " ".join(got.stdout.split())
    assert (
        "move_base: follower: goal tolerances xy 0.4 m, yaw 0.17 rad, from "
        "param/dwa_local_planner_params.yaml (launch/navigation.launch)"
    ) in flat
    assert "/mission/aruco_lookup_locations/target_1 = target 1 (param/our_targets.yaml" in flat
    assert "/mission/my_copy/t2 = target 2, known by its value" in flat
    ran = ros1_run.of(open_run(recorded))  # none of its nodes reads /fiducial_transforms
    assert ran is not None and ran.detections_read is False
    assert not grade_file(recorded).check("marker_0.detected").passed


def test_a_node_reads_the_graded_worlds_targets_from_its_private_parameters(
    recorded: Path,
) -> None:
    got = usar("log", str(recorded), "--node", "mission")
    assert got.returncode == 0, got.stderr
    # the world's target 1; its copy of the course's target 2 is gone (one-room has one)
    assert "mission: my target_1 is [1.1, 0.3], my copy of target 2 is None" in got.stdout


def test_amcl_pose_arrives_at_start_and_after_motion(recorded: Path) -> None:
    run = open_run(recorded)
    topic = contract.amcl_pose("explorer")
    assert run.topics[topic].msgtype == "geometry_msgs/msg/PoseWithCovarianceStamped"
    poses = [m for m in run.messages([topic]) if isinstance(m.msg, msgs.PoseWithCovarianceStamped)]
    first = poses[0].msg
    assert first.header.frame_id == "map"
    assert (first.pose.pose.position.x, first.pose.pose.position.y) == pytest.approx((-1.2, 0.6))
    assert poses[0].log_time_ns <= contract.START_TIME_NS + 200_000_000  # at start
    # the explorer drove 1.2 m east: its amcl updates every 0.1 m (its launch's update_min_d)
    moved = [p.msg.pose.pose.position.x for p in poses[1:]]
    assert len(moved) >= 8 and -0.25 < moved[-1] < 0.0  # it stopped 0.1 m short
    steps = [b - a for a, b in zip([-1.2, *moved], moved, strict=False)]
    assert all(s > 0.1 - 1e-9 for s in steps[:8]), steps
    said = usar("log", str(recorded), "--node", "mission").stdout
    assert "mission: 1 amcl poses at start" in said  # latched: the node got it
    assert f"mission: explorer ended 3, {len(poses)} amcl poses" in said, said


def test_the_users_explicit_tolerance_wins_over_the_packages(tmp_path: Path) -> None:
    """``--set mission.xy_tolerance=0.15``: the instructor's word over the package's 0.4."""
    pkg = nav_package.write(tmp_path / "src" / nav_package.NAME)
    world = tmp_path / "room.toml"
    save(one_room(), world)
    out = tmp_path / "set.mcap"
    done = usar(
        "record", "--scenario", str(world), "--ros1", str(pkg), "--launch", "go.launch",
        "--out", str(out), "--quiet", "--set", "xy_tolerance=0.15",
    )
    assert done.returncode == 0, done.stdout + done.stderr
    run = open_run(out)
    facts = ros1_run.of(run)
    assert facts is not None
    [follower] = [t for t in facts.goal_tolerances if t.robot == "follower"]
    assert (follower.xy, follower.yaw) == (0.15, 0.17)
    assert follower.source.startswith("xy: usar's setting mission.xy_tolerance; yaw: param/dwa")
    assert facts.applies("mission.xy_tolerance") and not facts.applies("mission.yaw_tolerance")
    [reached] = [
        m.log_time_ns
        for m in run.messages([contract.goal_status("follower")])
        if isinstance(m.msg, msgs.DiagnosticStatus) and m.msg.message == "succeeded"
    ]
    last = [
        m.msg.pose.position
        for m in run.messages([contract.truth_pose("follower")], reached)
        if isinstance(m.msg, msgs.PoseStamped)
    ][-1]
    assert math.hypot(last.x - 0.8, last.y + 0.9) <= 0.17
