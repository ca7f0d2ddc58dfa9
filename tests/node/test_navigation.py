"""node/navigation: the move_base-like client on the node API, in a closed loop with a plain
unicycle model of the robot (the test integrates the client's own ``cmd_vel``), tick by tick
through an executor, as the mission process drives it."""

from __future__ import annotations

import math

import pytest
from conftest import one_room

from usar_replay.core import contract, msgs
from usar_replay.core.rotations import quat_from_yaw
from usar_replay.node.executor import Executor
from usar_replay.node.navigation import NavigateClient, NavResult
from usar_replay.node.node import Node
from usar_replay.world.nav import PlanningGrid, grid_to_msg

S = 1_000_000_000
DT = S // 20  # the simulator's control rate
ROBOT = "explorer"


class Loop:
    """An executor with a node running a NavigateClient, and the robot's true pose."""

    def __init__(self, *, with_map: bool = True) -> None:
        self.ex = Executor()
        with self.ex.activate():
            self.node = Node("nav")
            self.nav = NavigateClient(self.node, ROBOT)
            self.node.create_subscription(msgs.String, "/go", lambda _: self._send())
        self.pending: list[msgs.PoseStamped] = []
        start = one_room().explorer
        self.pose = (start.x, start.y, start.yaw)
        self.t = S
        self.twist = msgs.Twist()
        self.outputs: list[tuple[str, msgs.Message]] = []
        self.results: list[NavResult] = []
        grid = PlanningGrid.from_scenario(one_room())
        self.map = grid_to_msg(grid, msgs.Time.from_ns(S)) if with_map else None
        self.step(first=True)

    def _inputs(self, first: bool) -> list[tuple[str, msgs.Message]]:
        stamp = msgs.Time.from_ns(self.t)
        x, y, yaw = self.pose
        base = msgs.TransformStamped(
            header=msgs.Header(stamp=stamp, frame_id=contract.odom_frame(ROBOT)),
            child_frame_id=contract.base_frame(ROBOT),
            transform=msgs.Transform(
                translation=msgs.Vector3(x=x, y=y), rotation=quat_from_yaw(yaw)
            ),
        )
        items: list[tuple[str, msgs.Message]] = [(contract.TF, msgs.TFMessage(transforms=(base,)))]
        if first:
            odom_in_map = msgs.TransformStamped(
                header=msgs.Header(stamp=stamp, frame_id=contract.MAP),
                child_frame_id=contract.odom_frame(ROBOT),
            )
            items.insert(0, (contract.TF_STATIC, msgs.TFMessage(transforms=(odom_in_map,))))
            if self.map is not None:
                items.insert(0, (contract.MAP_TOPIC, self.map))
        odom = msgs.Odometry(header=msgs.Header(stamp=stamp, frame_id=contract.odom_frame(ROBOT)))
        items.append((contract.odom(ROBOT), odom))
        return items

    def _send(self) -> None:
        self.nav.send_goal(self.pending.pop(), self.results.append, name="there", ignore_yaw=True)

    def step(self, *, first: bool = False) -> None:
        go: list[tuple[str, msgs.Message]] = [("/go", msgs.String())] if self.pending else []
        out = self.ex.tick(self.t, [*self._inputs(first), *go])
        self.outputs += out
        for topic, msg in out:
            if topic == contract.cmd_vel(ROBOT) and isinstance(msg, msgs.Twist):
                self.twist = msg
        x, y, yaw = self.pose  # the robot moves for one control period
        v, w, dt = self.twist.linear.x, self.twist.angular.z, DT / S
        self.pose = (x + v * math.cos(yaw) * dt, y + v * math.sin(yaw) * dt, yaw + w * dt)
        self.t += DT

    def goal(self, x: float, y: float, frame: str = contract.MAP) -> None:
        """Sent from a callback in the next tick, as a mission sends its goals."""
        goal = msgs.PoseStamped(
            header=msgs.Header(frame_id=frame), pose=msgs.Pose(position=msgs.Point(x=x, y=y))
        )
        self.pending.append(goal)
        self.step()

    def run(self, max_s: float) -> None:
        for _ in range(int(max_s * S / DT)):
            if self.results:
                return
            self.step()


def test_a_goal_is_driven_to_and_reported() -> None:
    loop = Loop()
    loop.goal(0.6, 0.6)
    assert loop.nav.active
    loop.run(30.0)
    [result] = loop.results
    assert result.succeeded and result.goal_name == "there" and result.reason == ""
    assert math.dist(loop.pose[:2], (0.6, 0.6)) <= 0.05 + 0.02
    cmd = [m for t, m in loop.outputs if t == contract.cmd_vel(ROBOT)]
    assert all(isinstance(m, msgs.Twist) and abs(m.linear.x) <= 0.26 + 1e-9 for m in cmd)
    assert cmd[-1] == msgs.Twist()  # it stops at the end
    status = [m for t, m in loop.outputs if t == contract.goal_status(ROBOT)]
    assert len(status) == 1
    assert any(t == contract.plan(ROBOT) for t, _ in loop.outputs)
    assert not loop.nav.active


def test_a_goal_inside_a_wall_is_aborted_with_a_reason() -> None:
    loop = Loop()
    loop.goal(2.075, 0.0)  # the east wall's centre line
    loop.run(5.0)
    [result] = loop.results
    assert not result.succeeded and result.status == "aborted" and result.reason


def test_a_goal_before_the_map_waits_for_it() -> None:
    loop = Loop(with_map=False)
    loop.goal(-0.5, 0.6)
    assert not loop.nav.active and loop.results == []
    loop.map = grid_to_msg(PlanningGrid.from_scenario(one_room()), msgs.Time.from_ns(loop.t))
    loop.step(first=True)  # the map arrives
    assert loop.nav.active
    loop.run(20.0)
    assert [r.succeeded for r in loop.results] == [True]


def test_a_goal_in_the_odom_frame_is_put_in_map() -> None:
    loop = Loop()
    loop.goal(-0.6, 0.6, frame=contract.odom_frame(ROBOT))  # odom is map here
    loop.run(20.0)
    assert [r.succeeded for r in loop.results] == [True]
    nowhere = msgs.PoseStamped(header=msgs.Header(frame_id="nowhere"))
    with pytest.raises(ValueError, match="'nowhere' cannot be looked up in map"):
        loop.nav.send_goal(nowhere)


def test_a_command_sent_on_success_is_the_last_of_its_tick() -> None:
    """As move_base (issue #32): the client's zero velocity and outcome come before the done
    callback runs, so a one-shot spin sent from it is the tick's last command and the robot
    turns."""
    loop = Loop()
    spin = msgs.Twist(angular=msgs.Vector3(z=0.3))
    with loop.ex.activate():
        own = loop.node.create_publisher(msgs.Twist, contract.cmd_vel(ROBOT))

    def spin_once(result: NavResult) -> None:
        loop.results.append(result)
        own.publish(spin)  # the mission's own publisher, once

    loop.pending.append(
        msgs.PoseStamped(
            header=msgs.Header(frame_id=contract.MAP),
            pose=msgs.Pose(position=msgs.Point(x=-0.7, y=0.6)),
        )
    )
    loop.nav.send_goal(loop.pending.pop(), spin_once, name="there", ignore_yaw=True)
    before = len(loop.outputs)
    loop.run(20.0)
    [result] = loop.results
    assert result.succeeded
    last_tick = [m for t, m in loop.outputs[before:] if t == contract.cmd_vel(ROBOT)][-2:]
    assert last_tick == [msgs.Twist(), spin]  # move_base's stop, then the spin
    yaw = loop.pose[2]
    for _ in range(20):
        loop.step()
    assert loop.pose[2] - yaw == pytest.approx(0.3, abs=1e-6)  # 1 s at 0.3 rad/s
