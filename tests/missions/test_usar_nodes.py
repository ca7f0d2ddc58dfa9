"""The built-in mission's nodes fed hand-made messages: no simulator, no process, no log.

Why: the mission is pure code over messages; these tests drive it tick by tick through the same
executor the mission process uses, and check what it publishes, so a behaviour change is caught
without a minute of simulation.
"""

from __future__ import annotations

import math

import pytest
from conftest import one_room

from usar_replay.core import contract, msgs
from usar_replay.core.rotations import quat_from_yaw
from usar_replay.core.settings import RunSettings
from usar_replay.missions import usar
from usar_replay.node.executor import Executor, PublishPolicy
from usar_replay.pipeline.record import mission_parameters
from usar_replay.world.nav import PlanningGrid, grid_to_msg

T0 = contract.START_TIME_NS
TICK = 50_000_000
SCENARIO = one_room()


def _tf(parent: str, child: str, t: int, x: float, y: float, yaw: float) -> msgs.TransformStamped:
    return msgs.TransformStamped(
        header=msgs.Header(stamp=msgs.Time.from_ns(t), frame_id=parent),
        child_frame_id=child,
        transform=msgs.Transform(translation=msgs.Vector3(x=x, y=y), rotation=quat_from_yaw(yaw)),
    )


def _static(t: int) -> msgs.TFMessage:
    items = []
    for start in (SCENARIO.explorer, SCENARIO.follower):
        r = start.name
        items.append(_tf(contract.MAP, contract.odom_frame(r), t, start.x, start.y, start.yaw))
    # the camera: 0.1 m ahead of base_footprint, optical frame z forward (REP-103)
    cam = msgs.TransformStamped(
        header=msgs.Header(stamp=msgs.Time.from_ns(t), frame_id=contract.base_frame("explorer")),
        child_frame_id=contract.OPTICAL_FRAME,
        transform=msgs.Transform(
            translation=msgs.Vector3(x=0.1, z=0.12),
            rotation=msgs.Quaternion(x=-0.5, y=0.5, z=-0.5, w=0.5),
        ),
    )
    return msgs.TFMessage(transforms=(*items, cam))


def _tick_inputs(
    t: int, poses: dict[str, tuple[float, float, float]]
) -> list[tuple[str, msgs.Message]]:
    """The simulator's /tf and odometry at ``t`` with robots at ``poses`` in their odom frames."""
    tf = msgs.TFMessage(
        transforms=tuple(
            _tf(contract.odom_frame(r), contract.base_frame(r), t, *poses[r])
            for r in contract.ROBOTS
        )
    )
    out: list[tuple[str, msgs.Message]] = [(contract.TF, tf)]
    for r in contract.ROBOTS:
        out.append(
            (
                contract.odom(r),
                msgs.Odometry(
                    header=msgs.Header(stamp=msgs.Time.from_ns(t), frame_id=contract.odom_frame(r)),
                    child_frame_id=contract.base_frame(r),
                ),
            )
        )
    return out


@pytest.fixture
def mission() -> Executor:
    ex = Executor(
        mission_parameters(SCENARIO, RunSettings()),
        PublishPolicy(contract.SIM_TOPICS, contract.sim_frames()),
    )
    with ex.activate():
        usar.Explorer()
        usar.Follower()
    return ex


def _topics(out: list[tuple[str, msgs.Message]]) -> list[str]:
    return [t for t, _ in out]


def test_the_first_tick_sends_the_explorer_to_target_1(mission: Executor) -> None:
    grid = PlanningGrid.from_scenario(SCENARIO)
    first = [
        (contract.TF_STATIC, _static(T0)),
        (contract.MAP_TOPIC, grid_to_msg(grid, msgs.Time.from_ns(T0))),
        *_tick_inputs(T0, {r: (0.0, 0.0, 0.0) for r in contract.ROBOTS}),
    ]
    with mission.activate():
        out = mission.tick(T0, first)
    topics = _topics(out)
    assert topics[0] == contract.ROSOUT  # "mission start"
    goal = dict(out)[contract.goal("explorer")]
    assert isinstance(goal, msgs.PoseStamped) and goal.header.frame_id == contract.MAP
    assert (goal.pose.position.x, goal.pose.position.y) == SCENARIO.targets[0]
    assert contract.plan("explorer") in topics
    # the explorer drives in the same tick (its odometry comes after the start), the follower waits
    assert contract.cmd_vel("explorer") in topics and contract.cmd_vel("follower") not in topics
    assert all(isinstance(m, msgs.Message) for _, m in out)


def _spinning(mission: Executor) -> int:
    """Run the explorer to target_1 by teleporting it there; return the sim time."""
    grid = PlanningGrid.from_scenario(SCENARIO)
    ex = SCENARIO.explorer
    tx, ty = SCENARIO.targets[0]
    here = {r: (0.0, 0.0, 0.0) for r in contract.ROBOTS}
    with mission.activate():
        mission.tick(
            T0,
            [
                (contract.TF_STATIC, _static(T0)),
                (contract.MAP_TOPIC, grid_to_msg(grid, msgs.Time.from_ns(T0))),
                *_tick_inputs(T0, here),
            ],
        )
        there = dict(here, explorer=(tx - ex.x, ty - ex.y, 0.0))
        t = T0
        for _ in range(200):
            t += TICK
            out = mission.tick(t, _tick_inputs(t, there))
            if any(isinstance(m, msgs.Log) and "searching for a marker" in m.msg for _, m in out):
                return t
    raise AssertionError("the explorer never started to search")


def _detection(t: int, marker_id: int, z: float) -> msgs.FiducialTransformArray:
    return msgs.FiducialTransformArray(
        header=msgs.Header(stamp=msgs.Time.from_ns(t), frame_id=contract.OPTICAL_FRAME),
        transforms=(
            msgs.FiducialTransform(
                fiducial_id=marker_id,
                transform=msgs.Transform(translation=msgs.Vector3(z=z)),
            ),
        ),
    )


def test_broadcast_and_store(mission: Executor) -> None:
    """Detections within range: marker_frame on /tf, child of the optical frame, stamped with
    the image's stamp, on each such frame; after 5 frames the median is stored in map."""
    t = _spinning(mission)
    tx, ty = SCENARIO.targets[0]
    ex = SCENARIO.explorer
    there = {"explorer": (tx - ex.x, ty - ex.y, 0.0), "follower": (0.0, 0.0, 0.0)}
    empty = msgs.FiducialTransformArray(
        header=msgs.Header(frame_id=contract.OPTICAL_FRAME), transforms=()
    )
    stored: msgs.FiducialTransformArray | None = None
    broadcasts: list[msgs.TransformStamped] = []
    with mission.activate():
        t += TICK
        out = mission.tick(t, [*_tick_inputs(t, there), (contract.FIDUCIALS, empty)])
        assert contract.TF not in _topics(out)  # no detection, no broadcast
        spin = dict(out)[contract.cmd_vel("explorer")]
        assert isinstance(spin, msgs.Twist) and spin.angular.z == pytest.approx(0.1)
        assert spin.linear.x == 0.0
        # a marker 10 m away is the known trap: refused, never broadcast
        t += TICK
        out = mission.tick(
            t, [*_tick_inputs(t, there), (contract.FIDUCIALS, _detection(t, 0, 10.0))]
        )
        assert contract.TF not in _topics(out)
        for _ in range(5):
            t += TICK
            out = mission.tick(
                t, [*_tick_inputs(t, there), (contract.FIDUCIALS, _detection(t, 0, 0.9))]
            )
            for topic, m in out:
                if topic == contract.TF:
                    assert isinstance(m, msgs.TFMessage)
                    broadcasts += list(m.transforms)
                if topic == contract.MARKER_POSES:
                    assert isinstance(m, msgs.FiducialTransformArray)
                    stored = m
    assert len(broadcasts) == 5
    for b in broadcasts:
        assert b.child_frame_id == contract.MARKER_FRAME
        assert b.header.frame_id == contract.OPTICAL_FRAME
    assert [b.header.stamp.ns for b in broadcasts] == sorted(
        {b.header.stamp.ns for b in broadcasts}
    )
    assert stored is not None and [f.fiducial_id for f in stored.transforms] == [0]
    p = stored.transforms[0].transform.translation
    # 0.9 m ahead of a camera 0.1 m ahead of the explorer at target_1, facing +x
    assert math.isclose(p.x, tx + 1.0, abs_tol=1e-9) and math.isclose(p.y, ty, abs_tol=1e-9)


def test_the_mission_may_not_publish_the_simulators_links() -> None:
    ex = Executor({}, PublishPolicy(contract.SIM_TOPICS, contract.sim_frames()))
    from usar_replay.node.node import Node

    with ex.activate():
        node = Node("rogue")
        with pytest.raises(PermissionError, match="ground truth"):
            node.create_publisher(msgs.PoseStamped, contract.truth_pose("explorer"))
        with pytest.raises(PermissionError, match="simulator"):
            node.create_publisher(msgs.Odometry, contract.odom("explorer"))
        pub = node.create_publisher(msgs.TFMessage, contract.TF)
        link = _tf(contract.odom_frame("explorer"), contract.base_frame("explorer"), T0, 0, 0, 0)
        with pytest.raises(PermissionError, match="tf link"):
            pub.publish(msgs.TFMessage(transforms=(link,)))
        with pytest.raises(PermissionError, match="ground truth"):
            node.create_subscription(msgs.PoseStamped, contract.truth_pose("explorer"), print)
