"""core/contract: the log contract's names agree with each other (frames, topics, the body)."""

from __future__ import annotations

import math

from usar_replay.core import contract as c


def test_per_robot_topics_name_their_robot() -> None:
    assert c.robot_of_topic("/follower/cmd_vel") == "follower"
    assert c.robot_of_topic(c.odom("explorer")) == "explorer"
    assert c.robot_of_topic(c.truth_pose(c.ROS2_ROBOT)) == c.ROS2_ROBOT
    assert c.robot_of_topic(c.TF) is None
    assert c.robot_of_topic("/intruder/cmd_vel") is None  # looked up, not split


def test_ground_truth_is_only_the_ground_truth_topics() -> None:
    assert all(c.is_ground_truth(t) for t in c.GROUND_TRUTH_TOPICS)
    assert not any(c.is_ground_truth(t) for t in c.SIM_TOPICS)
    assert not c.is_ground_truth("/ground_truthiness")
    assert c.truth_pose("explorer") == "/ground_truth/explorer/pose"


def test_the_simulators_frames_are_each_robots_usar_frames() -> None:
    frames = c.sim_frames()
    for robot in c.ROBOTS:
        f = c.RobotFrames.usar(robot)
        assert {f.odom, f.base, f.camera, f.optical} <= set(frames)
    assert c.RobotFrames.usar("explorer").camera == c.CAMERA_FRAME
    assert c.RobotFrames.usar("explorer").optical == c.OPTICAL_FRAME
    assert c.MARKER_FRAME not in frames and c.MAP not in frames
    assert len(frames) == 4 * len(c.ROBOTS)


def test_the_body_radii_cover_the_footprint() -> None:
    body = c.WAFFLE
    corners = body.footprint
    assert max(math.hypot(x, y) for x, y in corners) <= body.radius
    assert max(math.hypot(x - body.body_offset, y) for x, y in corners) <= body.body_radius
    assert 0 < body.max_linear < body.max_angular


def test_the_sim_clock_starts_after_zero() -> None:
    assert c.START_TIME_NS == 1_000_000_000
    assert c.MISSION_COPIES[c.ARUCO_MARKERS] == c.MISSION_ARUCO_MARKERS
