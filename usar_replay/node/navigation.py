"""A move_base-like navigation action for one robot, built on the node API and nothing else.

Why it is a library on :class:`usar_replay.node.node.Node` rather than part of the simulator: in the
course, move_base is a node the students' code sends goals to; here it runs in the mission's
process, with the same inputs any node gets (``/map``, ``/tf``, the robot's odometry) and the
same outputs (``cmd_vel``, the goal, the plan, the goal's outcome). User code may use it or drive
``cmd_vel`` itself. The built-in mission uses it exactly as a user would.

Use::

    nav = NavigateClient(node, "explorer")
    nav.send_goal(pose_stamped_in_map, done_callback=on_done)   # on_done(NavResult)

While a goal is active the client publishes ``/<robot>/cmd_vel`` on each odometry message (the
simulator's control rate); when it ends it publishes a zero ``cmd_vel``, the outcome on
``/<robot>/goal_status`` (``diagnostic_msgs/DiagnosticStatus``: succeeded, or failed with a
reason) and a log line, then calls ``done_callback``. Idle, it publishes nothing, so another
publisher (a spin) can drive the robot.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from usar_replay.core import contract, msgs
from usar_replay.core.rotations import quat_from_yaw, yaw_from_quat
from usar_replay.node.node import Node, Time
from usar_replay.node.tf2 import Buffer, TransformException, TransformListener
from usar_replay.world.nav import (
    DriveLimits,
    Navigator,
    NavStatus,
    PlanningGrid,
    goal_status,
    grid_from_msg,
)

__all__ = ["NavResult", "NavigateClient"]

SUCCEEDED = "succeeded"
ABORTED = "aborted"


@dataclass(frozen=True, slots=True)
class NavResult:
    """How a goal ended: ``status`` is ``succeeded`` or ``aborted`` (with a ``reason``)."""

    goal_name: str
    status: str
    reason: str
    pose: tuple[float, float, float] | None
    """The robot's (x, y, yaw) in ``map`` when the goal ended."""

    @property
    def succeeded(self) -> bool:
        return self.status == SUCCEEDED


class NavigateClient:
    """move_base for ``robot``, driven by its odometry; see the module docstring."""

    def __init__(
        self,
        node: Node,
        robot: str,
        *,
        buffer: Buffer | None = None,
        limits: DriveLimits | None = None,
        xy_tolerance: float = 0.05,
        yaw_tolerance: float = 0.17,
        base_frame: str | None = None,
    ) -> None:
        """``base_frame``: the robot's base frame in tf (default ``<robot>_tf/base_footprint``,
        the US&R naming; the ROS 2 project's is ``robot1/base_footprint``). The client finds
        the robot by looking that frame up in ``map``: without a connected tf tree it cannot."""
        self.node = node
        self.robot = robot
        self.base_frame = base_frame or contract.base_frame(robot)
        self.limits = limits or DriveLimits()
        self.xy_tolerance = xy_tolerance
        self.yaw_tolerance = yaw_tolerance
        if buffer is None:
            buffer = Buffer(cache_time=30.0)
            TransformListener(buffer, node)
        self.buffer = buffer
        self.grid: PlanningGrid | None = None
        self._base_grid: PlanningGrid | None = None
        self._discs: list[tuple[float, float, float]] = []
        self._nav: Navigator | None = None
        self.pose: tuple[float, float, float] | None = None
        self._goal_name = ""
        self._goal_seq = 0
        self._started_ns = 0
        self._done: Callable[[NavResult], None] | None = None
        self._waiting: tuple[Any, ...] | None = None
        self._cmd = node.create_publisher(msgs.Twist, contract.cmd_vel(robot))
        self._goal_pub = node.create_publisher(msgs.PoseStamped, contract.goal(robot))
        self._plan_pub = node.create_publisher(msgs.Path, contract.plan(robot))
        self._status_pub = node.create_publisher(msgs.DiagnosticStatus, contract.goal_status(robot))
        node.create_subscription(msgs.OccupancyGrid, contract.MAP_TOPIC, self._on_map)
        node.create_subscription(msgs.Odometry, contract.odom(robot), self._on_odom)

    # -- the map ---------------------------------------------------------------------------------

    def _on_map(self, msg: msgs.OccupancyGrid) -> None:
        self._base_grid = grid_from_msg(msg)
        self._rebuild()
        if self._waiting is not None:
            goal, done, name, ignore_yaw, xy, yt = self._waiting
            self._waiting = None
            self._goal_seq -= 1
            self.send_goal(
                goal, done, name=name, ignore_yaw=ignore_yaw, xy_tolerance=xy, yaw_tolerance=yt
            )

    def mark_obstacle(self, x: float, y: float, radius: float) -> None:
        """Add a round obstacle to this robot's costmap, as its laser would mark another robot
        standing at (x, y) (the map has only walls and fixed obstacles)."""
        self._discs.append((x, y, radius))
        self._rebuild()

    def _rebuild(self) -> None:
        if self._base_grid is None:
            return
        self.grid = self._base_grid.with_discs(self._discs) if self._discs else self._base_grid
        self._nav = Navigator(self.grid, self.limits)

    # -- goals -----------------------------------------------------------------------------------

    @property
    def active(self) -> bool:
        return self._nav is not None and self._nav.status is NavStatus.ACTIVE

    def send_goal(
        self,
        goal: msgs.PoseStamped,
        done_callback: Callable[[NavResult], None] | None = None,
        *,
        name: str = "",
        ignore_yaw: bool = False,
        xy_tolerance: float | None = None,
        yaw_tolerance: float | None = None,
    ) -> None:
        """Drive to ``goal`` (in ``map``, or a frame tf links to ``map``, such as the robot's
        odom frame: it is transformed into ``map`` with the latest transform);
        ``done_callback(NavResult)`` when it ends.

        ``ignore_yaw``: any final heading will do. A new goal replaces an active one (its
        callback is not called, as move_base preempts).
        """
        goal = self._in_map(goal)
        self._goal_seq += 1
        self._goal_name = name or f"goal_{self._goal_seq}"
        self._done = done_callback
        p = goal.pose.position
        yaw = None if ignore_yaw else yaw_from_quat(goal.pose.orientation)
        xy = self.xy_tolerance if xy_tolerance is None else xy_tolerance
        yt = self.yaw_tolerance if yaw_tolerance is None else yaw_tolerance
        t_ns = self.node.get_clock().now().nanoseconds
        self._started_ns = t_ns
        stamp = msgs.Time.from_ns(t_ns)
        header = msgs.Header(stamp=stamp, frame_id=contract.MAP)
        self._goal_pub.publish(
            msgs.PoseStamped(
                header=header,
                pose=msgs.Pose(
                    position=msgs.Point(x=p.x, y=p.y), orientation=quat_from_yaw(yaw or 0.0)
                ),
            )
        )
        if self._nav is None:
            # as move_base waits for its costmap: the goal starts when /map arrives
            self._waiting = (goal, done_callback, self._goal_name, ignore_yaw, xy, yt)
            return
        if self.pose is None:  # a goal before this robot's first odometry: ask tf
            self.pose = self._lookup_pose(stamp)
        path = self._nav.set_goal(
            p.x, p.y, yaw, xy_tolerance=xy, yaw_tolerance=yt, t_ns=t_ns, start=self.pose
        )
        if path:
            self._plan_pub.publish(
                msgs.Path(
                    header=header,
                    poses=tuple(
                        msgs.PoseStamped(
                            header=header, pose=msgs.Pose(position=msgs.Point(x=px, y=py))
                        )
                        for px, py in path
                    ),
                )
            )
        self.node.get_logger().info(
            f"{self.robot}: goal {self._goal_name} at ({p.x:.3f}, {p.y:.3f})"
        )
        if self._nav.status is NavStatus.FAILED:
            self._finish(NavStatus.FAILED, self._nav.reason)

    def _in_map(self, goal: msgs.PoseStamped) -> msgs.PoseStamped:
        frame = goal.header.frame_id.lstrip("/")
        if frame == contract.MAP:
            return goal
        try:
            tf = self.buffer.lookup_transform(contract.MAP, frame, Time())
        except TransformException as err:
            raise ValueError(
                f"navigation goals are in {contract.MAP!r} or a frame tf links to it; "
                f"{frame!r} cannot be looked up in map now: {err}"
            ) from err
        tr, q = tf.transform.translation, tf.transform.rotation
        yaw = yaw_from_quat(q)
        p = goal.pose.position
        c, s = math.cos(yaw), math.sin(yaw)
        return msgs.PoseStamped(
            header=msgs.Header(stamp=goal.header.stamp, frame_id=contract.MAP),
            pose=msgs.Pose(
                position=msgs.Point(x=tr.x + c * p.x - s * p.y, y=tr.y + s * p.x + c * p.y),
                orientation=quat_from_yaw(yaw + yaw_from_quat(goal.pose.orientation)),
            ),
        )

    def cancel_goal(self) -> None:
        """Stop driving now; the done callback is not called."""
        if self._nav is not None and self.active:
            self._nav.cancel()
            self._cmd.publish(msgs.Twist())

    # -- driving ---------------------------------------------------------------------------------

    def _lookup_pose(self, stamp: msgs.Time) -> tuple[float, float, float] | None:
        try:
            tf = self.buffer.lookup_transform(contract.MAP, self.base_frame, Time.from_msg(stamp))
        except TransformException:
            return None
        tr = tf.transform.translation
        return (tr.x, tr.y, yaw_from_quat(tf.transform.rotation))

    def _on_odom(self, msg: msgs.Odometry) -> None:
        pose = self._lookup_pose(msg.header.stamp)
        if pose is None:
            return
        self.pose = pose
        nav = self._nav
        if nav is None or nav.status is not NavStatus.ACTIVE:
            return
        t_ns = msg.header.stamp.ns
        twist = nav.update(t_ns, *pose)
        self._cmd.publish(twist)
        if nav.status is not NavStatus.ACTIVE:
            self._finish(nav.status, nav.reason)

    def _finish(self, status: NavStatus, reason: str) -> None:
        ok = status is NavStatus.SUCCEEDED
        t_ns = self.node.get_clock().now().nanoseconds
        self._cmd.publish(msgs.Twist())
        self._status_pub.publish(
            goal_status(
                self.robot,
                self._goal_name,
                self._goal_seq,
                ok,
                reason,
                self.pose,
                self._started_ns,
                t_ns,
            )
        )
        text = f"{self.robot}: goal {self._goal_name} " + ("reached" if ok else f"failed: {reason}")
        if ok:
            self.node.get_logger().info(text)
        else:
            self.node.get_logger().warning(text)
        done, self._done = self._done, None
        if done is not None:
            done(NavResult(self._goal_name, SUCCEEDED if ok else ABORTED, reason, self.pose))
