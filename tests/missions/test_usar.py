"""The built-in mission's own ideas (missions/usar.py): approach points, range gate, no marker."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from conftest import one_room
from scipy.spatial.transform import Rotation

from usar_replay.core import msgs
from usar_replay.core.settings import MissionSettings, RunSettings
from usar_replay.log import bag
from usar_replay.log.run import open_run
from usar_replay.missions.usar import approach_point
from usar_replay.pipeline.record import record
from usar_replay.pipeline.replay import replay
from usar_replay.world.nav import PlanningGrid, robot_disc
from usar_replay.world.scenario import Marker, course_world

COURSE = course_world()
GRID = PlanningGrid.from_scenario(COURSE)


def _optical_quat(m: Marker) -> msgs.Quaternion:
    """A marker's orientation in map as the detector reports it: +z out of its face."""
    face = np.array([math.cos(m.yaw), math.sin(m.yaw), 0.0])
    up = np.array([0.0, 0.0, 1.0])
    rot = np.column_stack([np.cross(up, face), up, face])  # x right, y up, z out of the face
    x, y, z, w = Rotation.from_matrix(rot).as_quat()
    return msgs.Quaternion(x=x, y=y, z=z, w=w)


@pytest.mark.parametrize("mid", [0, 1, 2, 3])
def test_course_approach_points_are_free_in_front_and_within_tolerance(mid: int) -> None:
    m = COURSE.marker_by_id(mid)
    settings = MissionSettings()
    goal = approach_point(GRID, (m.x, m.y), _optical_quat(m), settings)
    assert goal is not None
    gx, gy, gyaw = goal
    assert GRID.is_free(gx, gy)
    assert math.dist((gx, gy), (m.x, m.y)) <= settings.follower_tolerance
    # in front of the face, and the robot faces the marker
    assert (gx - m.x) * math.cos(m.yaw) + (gy - m.y) * math.sin(m.yaw) > 0
    bearing = math.atan2(m.y - gy, m.x - gx)
    assert abs(math.remainder(gyaw - bearing, 2 * math.pi)) < 0.2


def test_approach_point_beside_a_blocking_obstacle() -> None:
    """A box stands in front of the marker: the follower stops beside it, still within reach
    and in sight of the marker, never behind the box."""
    m = COURSE.marker_by_id(2)  # east outer wall at x 8.46, facing -x
    box = dataclasses.replace(
        COURSE.boxes[0], name="blocker", x=m.x - 0.45, y=m.y, size_x=0.1, size_y=0.1
    )
    grid = PlanningGrid.from_scenario(dataclasses.replace(COURSE, boxes=(*COURSE.boxes, box)))
    assert not any(grid.is_free(m.x - d, m.y) for d in np.arange(0.25, 0.7, 0.05))
    settings = MissionSettings(follower_tolerance=0.8)
    goal = approach_point(grid, (m.x, m.y), _optical_quat(m), settings)
    assert goal is not None
    gx, gy, _ = goal
    assert grid.is_free(gx, gy)
    assert abs(gy - m.y) > 0.2  # beside the blocked normal ...
    assert math.dist((gx, gy), (m.x, m.y)) <= 0.8 - settings.xy_tolerance  # ... within reach


def test_no_free_point_gives_none() -> None:
    m = COURSE.marker_by_id(1)
    buried = np.ones_like(GRID.occupied)
    grid = PlanningGrid(buried, GRID.origin, GRID.resolution)
    assert approach_point(grid, (m.x, m.y), _optical_quat(m), MissionSettings()) is None


def test_a_marker_beyond_range_is_refused_and_the_mission_goes_on(tmp_path: Path) -> None:
    """With a range gate shorter than the room's marker distance (0.9 m), the explorer turns a
    full circle at 0.1 rad/s, reports the target, goes home, and the follower still runs."""
    settings = RunSettings(mission=MissionSettings(max_detection_range=0.5))
    result = record(one_room(), tmp_path / "gated.mcap", settings)
    assert result.mission_done and result.markers_found == {}
    detections, broadcasts, spins = 0, 0, 0
    lines: list[str] = []
    for m in bag.BagReader(tmp_path / "gated.mcap").messages(
        ["/fiducial_transforms", "/tf", "/explorer/cmd_vel", "/rosout"]
    ):
        if isinstance(m.msg, msgs.FiducialTransformArray):
            detections += len(m.msg.transforms)
        elif isinstance(m.msg, msgs.TFMessage):
            broadcasts += sum(t.child_frame_id == "marker_frame" for t in m.msg.transforms)
        elif isinstance(m.msg, msgs.Twist) and m.msg.angular.z == 0.1:
            assert m.msg.linear.x == 0.0
            spins += 1
        elif isinstance(m.msg, msgs.Log):
            lines.append(m.msg.msg)
    assert detections > 0  # the marker was seen ...
    assert broadcasts == 0  # ... but never accepted, so never broadcast
    # a full turn at 0.1 rad/s takes about 63 s: ~1260 control ticks at 20 Hz
    assert spins >= 2 * math.pi / 0.1 * 20 * 0.95
    assert any("no marker found at target_1 after a full turn" in s for s in lines)
    assert lines[-1] == "mission complete"
    # the log carries its non-default setting, and replay uses it: bit for bit, no flag needed
    run = open_run(tmp_path / "gated.mcap")
    assert run.settings_recorded and run.settings.mission.max_detection_range == 0.5
    report = replay(run)
    assert report.identical and not report.regression, report.lines()


def test_the_approach_point_keeps_clear_of_the_parked_explorer() -> None:
    """Seed 5 put a marker beside the explorer's home: the follower's map has the parked
    explorer in it, so its goal is where it fits, not against the other robot."""
    m = COURSE.marker_by_id(1)
    settings = MissionSettings()
    free_goal = approach_point(GRID, (m.x, m.y), _optical_quat(m), settings)
    assert free_goal is not None
    reach = settings.follower_tolerance - settings.xy_tolerance
    # the explorer parked beside the best spot: the goal moves to the other side, still in reach
    beside = robot_disc(free_goal[0] + 0.064 + 0.45, free_goal[1], 0.0)
    goal = approach_point(GRID.with_discs([beside]), (m.x, m.y), _optical_quat(m), settings)
    assert goal is not None and goal[:2] != free_goal[:2]
    assert math.dist(goal[:2], beside[:2]) >= beside[2] + GRID.robot_radius
    assert math.dist(goal[:2], (m.x, m.y)) <= reach
    # parked right on it: no spot in reach is left, the nearest clear one is the best there is
    on = robot_disc(free_goal[0] + 0.064, free_goal[1], 0.0)
    goal = approach_point(GRID.with_discs([on]), (m.x, m.y), _optical_quat(m), settings)
    assert goal is not None
    assert math.dist(goal[:2], on[:2]) >= on[2] + GRID.robot_radius
    assert reach < math.dist(goal[:2], (m.x, m.y)) <= settings.approach_max
