"""``/<robot>/move_base``: move_base's action, served by usar's navigator (bridge process only).

Why here and not in the simulator: in the course, move_base is a node the students' action
clients talk to; usar's :class:`usar_replay.world.nav.Navigator` is the same planner and
controller the Python node API's navigation client uses, so a ROS 1 package and a Python
mission drive alike. The server follows actionlib's rules as move_base does:

* a new goal preempts the active one (its client sees PREEMPTED);
* a cancel stops the robot (PREEMPTED/RECALLED as actionlib decides);
* feedback (``base_position``) on every control tick while active;
* SUCCEEDED when the goal is reached, ABORTED with the planner's or controller's reason
  (goal in collision and no free cell near it, no path, stuck) otherwise.

A goal is first decided as the package's global planner decides it (:func:`planned_goal`,
:func:`usar_replay.world.nav.course_goal`): a goal whose costmap cell is in an obstacle or within
the footprint's inscribed radius of one (the package's ``footprint``/``robot_radius``,
``footprint_padding``, ``inflation_radius``, its planner's ``default_tolerance``:
:attr:`MoveBase.goal_limits`, read by :func:`usar_replay.ros1.nav_params.goal_limits`; the
course template's by default) has no plan and is ABORTED, never moved (issue 43: a package
sending its explorer "home" to (0, 0), inside the course's walls, hung there on Gazebo; issue
51: a follower goal 0.11 m from a cylinder's surface had no plan on the course, and the package
waited there). A plannable goal
inside usar's own clearance (the circumscribed radius its controller keeps free, wider than
the footprint's inscribed radius) is moved to the nearest free cell within
:data:`GOAL_TOLERANCE_M`, as the course's robot drives up to such a goal. The other robot,
where tf says it stands when the goal arrives, is an obstacle in this robot's costmap, as its
laser would mark it.

Order, as move_base's own code has it: each control cycle publishes the feedback first; at a
goal's end, move_base's ``resetState()`` publishes the zero velocity and only then does
``as_->setSucceeded()`` (or ``setAborted``) send the result, which actionlib publishes before
its status array. So :meth:`MoveBase.tick` hands back what it published up to its last result
of the tick apart from what it published after it: a package that reacts to SUCCEEDED with a
command (a one-shot spin) commands after move_base's zero velocity, and the robot follows it.

Threads: actionlib calls back on its own threads; those callbacks only queue events, and
:meth:`MoveBase.tick` (the bridge's main loop, once per control tick) handles them in arrival
order, so the navigator itself is only ever touched by one thread.
"""

from __future__ import annotations

import math
import queue
from typing import Any

from usar_replay.core import contract, msgs
from usar_replay.core.rotations import quat_from_yaw, yaw_from_quat
from usar_replay.world.nav import (
    TEMPLATE_GOAL_LIMITS,
    DriveLimits,
    GoalLimits,
    Navigator,
    NavStatus,
    PlanningGrid,
    course_goal,
    goal_status,
    robot_disc,
)

__all__ = ["GOAL_TOLERANCE_M", "MoveBase", "planned_goal"]

GOAL_TOLERANCE_M = 0.25
"""How far a plannable goal inside usar's clearance may be moved to a free cell. The course
template's planner treats as obstacle only the cells within the footprint's inscribed radius
(0.087 m for the template's offset footprint, padded), while usar's costmap keeps the
circumscribed radius (:data:`usar_replay.world.nav.ROBOT_RADIUS`, 0.26 m) clear: a goal up to
0.26 - 0.087 plus one 0.05 m cell (0.23 m) inside usar's clear zone is one move_base plans
to."""

Pose = tuple[float, float, float]


def planned_goal(
    grid: PlanningGrid, x: float, y: float, limits: GoalLimits = TEMPLATE_GOAL_LIMITS
) -> tuple[tuple[float, float] | None, str]:
    """Where usar's navigator drives for a goal at (x, y): ``(None, why)`` where the package's
    global planner has no plan to it (move_base aborts it); else the goal (the plannable cell
    ``default_tolerance`` reached), moved to usar's nearest free cell within
    :data:`GOAL_TOLERANCE_M` where it is inside usar's clearance."""
    goal, why = course_goal(grid, x, y, limits)
    if goal is None:
        return None, why
    if not grid.is_free(*goal):
        near = grid.nearest_free(goal[0], goal[1], GOAL_TOLERANCE_M)
        if near is not None:
            return near, ""
    return goal, ""


class MoveBase:
    """One robot's move_base action server (see the module docstring)."""

    def __init__(self, robot: str, *, xy_tolerance: float, yaw_tolerance: float) -> None:
        import actionlib
        from move_base_msgs.msg import MoveBaseAction

        self.robot = robot
        self.xy_tolerance = xy_tolerance
        self.yaw_tolerance = yaw_tolerance
        self.goal_limits = TEMPLATE_GOAL_LIMITS
        """The package's costmap and global planner parameters that decide which goals have
        a plan (the bridge sets them from the launch file's, :mod:`.nav_params`)."""
        self.grid: PlanningGrid | None = None
        self.nav: Navigator | None = None
        self.active: Any = None
        self._events: queue.SimpleQueue[tuple[str, Any]] = queue.SimpleQueue()
        self._name = ""
        self._seq = 0
        self._started_ns = 0
        self.server = actionlib.ActionServer(
            f"/{robot}/move_base", MoveBaseAction, self._on_goal, self._on_cancel, auto_start=False
        )
        self.server.start()

    # -- actionlib's threads: queue only ----------------------------------------------------------

    def _on_goal(self, handle: Any) -> None:
        self._events.put(("goal", handle))

    def _on_cancel(self, handle: Any) -> None:
        self._events.put(("cancel", handle))

    # -- the bridge's loop -------------------------------------------------------------------------

    def tick(
        self,
        t_ns: int,
        poses: dict[str, Pose | None],
        in_map: Any,
    ) -> tuple[list[tuple[str, msgs.Message]], list[tuple[str, msgs.Message]]]:
        """Handle the queued goals and cancels, then drive one tick; what to publish (the
        ``cmd_vel``, the goal, the outcome) as usar messages, in two parts: ``(before, after)``.
        ``before`` is everything up to and including the tick's last result (a goal's last
        command, the zero velocity, its outcome): it precedes whatever the package published in
        the tick, which may react to that result. ``after`` is the active goal's command (and
        its start), later than the package's own command of the tick. ``in_map(frame)`` gives a
        frame's pose in map ((x, y, yaw) or None), for goals in another frame."""
        out: list[tuple[str, msgs.Message]] = []
        ended = 0  # out[:ended]: published up to the tick's last result
        while True:
            try:
                kind, handle = self._events.get_nowait()
            except queue.Empty:
                break
            if kind == "goal":
                out += self._start(handle, t_ns, poses, in_map)
                if self.active is None:  # it ended at once (no map, not linked, no path)
                    ended = len(out)
            elif self.active is not None and _same(handle, self.active):
                if self.nav is not None:
                    self.nav.cancel()
                out.append((contract.cmd_vel(self.robot), msgs.Twist()))  # before the result
                self.active.set_canceled(_result(), "cancelled by the client")
                self.active = None
                ended = len(out)
            else:
                handle.set_canceled(_result(), "cancelled by the client")
        pose = poses.get(self.robot)
        if self.active is None or self.nav is None or pose is None:
            return out[:ended], out[ended:]
        self._feedback(pose)  # move_base's cycle: the feedback first, then the command
        twist = self.nav.update(t_ns, *pose)
        out.append((contract.cmd_vel(self.robot), twist))
        if self.nav.status is not NavStatus.ACTIVE:
            out += self._finish(self.nav.status is NavStatus.SUCCEEDED, self.nav.reason, t_ns, pose)
            ended = len(out)
        return out[:ended], out[ended:]

    def _feedback(self, pose: Pose) -> None:
        from move_base_msgs.msg import MoveBaseFeedback

        from usar_replay.ros1.convert import to_ros1

        fb = MoveBaseFeedback()
        fb.base_position = to_ros1(_pose_stamped(pose, 0))
        self.active.publish_feedback(fb)

    def _start(
        self, handle: Any, t_ns: int, poses: dict[str, Pose | None], in_map: Any
    ) -> list[tuple[str, msgs.Message]]:
        out: list[tuple[str, msgs.Message]] = []
        if self.active is not None:
            self.active.set_canceled(_result(), "preempted by a new goal")
            self.active = None
        handle.set_accepted("")
        self._seq += 1
        self._name = f"goal_{self._seq}"
        self._started_ns = t_ns
        goal = handle.get_goal().target_pose
        p, q = goal.pose.position, goal.pose.orientation
        x, y = float(p.x), float(p.y)
        yaw = yaw_from_quat(msgs.Quaternion(x=q.x, y=q.y, z=q.z, w=q.w))
        frame = str(goal.header.frame_id).lstrip("/")
        self.active = handle
        if frame != contract.MAP:
            base = in_map(frame)
            if base is None:
                return self._finish(False, f"goal frame {frame!r} is not linked to map", t_ns)
            bx, by, byaw = base
            c, s = math.cos(byaw), math.sin(byaw)
            x, y, yaw = bx + c * x - s * y, by + s * x + c * y, yaw + byaw
        out.append((contract.goal(self.robot), _pose_stamped((x, y, yaw), t_ns)))
        if self.grid is None:
            return out + self._finish(False, "no map received yet", t_ns)
        discs = [robot_disc(*pz) for r, pz in poses.items() if r != self.robot and pz]
        grid = self.grid.with_discs(discs) if discs else self.grid
        goal, why = planned_goal(grid, x, y, self.goal_limits)
        if goal is None:  # as the course's global_planner: no plan, move_base aborts
            self.nav = None
            return out + self._finish(False, why, t_ns)
        x, y = goal
        self.nav = Navigator(grid, DriveLimits())
        path = self.nav.set_goal(
            x,
            y,
            yaw,
            xy_tolerance=self.xy_tolerance,
            yaw_tolerance=self.yaw_tolerance,
            t_ns=t_ns,
            start=poses.get(self.robot),
        )
        if path:
            header = msgs.Header(stamp=msgs.Time.from_ns(t_ns), frame_id=contract.MAP)
            out.append(
                (
                    contract.plan(self.robot),
                    msgs.Path(
                        header=header,
                        poses=tuple(_pose_stamped((px, py, 0.0), t_ns) for px, py in path),
                    ),
                )
            )
        if self.nav.status is NavStatus.FAILED:
            out += self._finish(False, self.nav.reason, t_ns)
        return out

    def _finish(
        self, ok: bool, reason: str, t_ns: int, pose: Pose | None = None
    ) -> list[tuple[str, msgs.Message]]:
        """The goal's end as move_base's: the zero velocity first (``resetState()``), then the
        result (``setSucceeded``/``setAborted``; actionlib publishes it, then its status)."""
        handle, self.active = self.active, None
        stop = (contract.cmd_vel(self.robot), msgs.Twist())
        if ok:
            handle.set_succeeded(_result(), "goal reached")
        else:
            handle.set_aborted(_result(), reason)
        status = goal_status(
            self.robot, self._name, self._seq, ok, reason, pose, self._started_ns, t_ns
        )
        return [stop, (contract.goal_status(self.robot), status)]


def _same(a: Any, b: Any) -> bool:
    return bool(a.get_goal_id().id == b.get_goal_id().id)


def _result() -> Any:
    """An empty MoveBaseResult (actionlib publishes None as a broken message)."""
    from move_base_msgs.msg import MoveBaseResult

    return MoveBaseResult()


def _pose_stamped(pose: Pose, t_ns: int) -> msgs.PoseStamped:
    return msgs.PoseStamped(
        header=msgs.Header(stamp=msgs.Time.from_ns(t_ns), frame_id=contract.MAP),
        pose=msgs.Pose(
            position=msgs.Point(x=pose[0], y=pose[1]), orientation=quat_from_yaw(pose[2])
        ),
    )
