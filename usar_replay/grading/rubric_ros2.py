"""The ROS 2 final project's rubric (60 points), checked from a log and its ground truth.

Same shape as the US&R rubric (:mod:`usar_replay.grading.grade`): a streaming :class:`Grader` fed
one message at a time (a recorded log, or the outputs a replay recomputes), lines as
:class:`~usar_replay.grading.grade.Check` with the measured value, the threshold and the sim time of
the evidence. The robot is judged by the simulator's ground truth (``/ground_truth/robot1/pose``),
never by what the mission believes; the ``final_destination`` frame by looking it up in ``map``
with tf2's rules over everything on ``/tf_static`` and ``/tf``; the marker by the course's
detector (``/aruco_markers`` as the world published it, the ``sim`` publisher: the recorder runs
ros2_aruco on the recorded frames, :mod:`usar_replay.pipeline.course_detector`), never by what a
mission publishes (its own copy is ``/mission/aruco_markers``, which the rubric does not read).

===============================  ======  ==========================================================
line (``Check.id``)              points  passes when
===============================  ======  ==========================================================
``tf.odom_to_base``              10      the mission broadcast ``robot1/odom ->
                                         robot1/base_footprint`` and every such broadcast equals
                                         ``/robot1/odom`` at the same stamp (within
                                         :data:`ODOM_MATCH_M` and :data:`ODOM_MATCH_RAD`): the tree
                                         is connected and consistent with odometry
``aruco_target.reached``         10      the robot came within ``target_reached_m`` of
                                         ``aruco_target``
``marker.detected``              10      the course's detector's ``/aruco_markers`` held the
                                         world's marker ID after the robot reached
                                         ``aruco_target``
``destination.chosen``           10      the first ``final_destination`` broadcast carries
                                         ``final_destination.aruco_<ID>`` for the detected ID
``final_destination.broadcast``  10      every ``final_destination`` broadcast is a child of
                                         ``final_destination.frame_id`` and, looked up in ``map``,
                                         lies within ``marker_map_error_m`` of the true destination
``destination.reached``          6       after the marker was detected, the robot came within
                                         ``target_reached_m`` of the true destination
``time_limit``                   4       the destination was reached within the time limit
===============================  ======  ==========================================================

The thresholds are the US&R rubric's (:class:`~usar_replay.grading.grade.Thresholds`), so a TA's
``[thresholds]`` file applies to both assignments.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

from usar_replay.core import contract, msgs
from usar_replay.core.rotations import wrap_angle, yaw_from_quat
from usar_replay.core.settings import Thresholds
from usar_replay.core.tf_tree import BufferCore, BufferFeeder, TransformException
from usar_replay.grading.verdict import Check, FoundMarker, GradeReport, Rubric
from usar_replay.world.ros2_world import task_of
from usar_replay.world.scenario import Scenario

__all__ = ["GRADE_TOPICS", "NO_DETECTOR", "POINTS", "REQUIRED_TOPICS", "RUBRIC", "Grader"]

TRUTH = contract.truth_pose(contract.ROS2_ROBOT)
ODOM = contract.odom(contract.ROS2_ROBOT)
GRADE_TOPICS = (contract.TF_STATIC, contract.TF, contract.ARUCO_MARKERS, ODOM, TRUTH)
"""The topics the grader reads; everything else is skipped without decoding."""
REQUIRED_TOPICS = (TRUTH, ODOM)
"""Without these a log cannot be graded: the simulator writes them from the first tick.
``/tf`` is the mission's and ``/aruco_markers`` the course's detector's, only for frames with a
marker: a log without them is graded, and fails the lines that need them (the detection line
saying so: :data:`NO_DETECTOR`)."""
NO_DETECTOR = (
    f"nothing on {contract.ARUCO_MARKERS}: the course's detector never saw a marker "
    "(did the robot turn the camera toward it?)"
)
"""What ``marker.detected`` measures when the course's detector never published on
``/aruco_markers`` (it publishes only frames with a marker)."""
POINTS = {
    "tf.odom_to_base": 10.0,
    "aruco_target.reached": 10.0,
    "marker.detected": 10.0,
    "destination.chosen": 10.0,
    "final_destination.broadcast": 10.0,
    "destination.reached": 6.0,
    "time_limit": 4.0,
}
ODOM_MATCH_M = 0.01
"""m; a broadcast ``odom -> base_footprint`` must match the odometry this closely."""
ODOM_MATCH_RAD = 0.02
ODOM_MEMORY = 64
"""Odometry poses kept by stamp for matching broadcasts (the broadcaster answers each at once)."""
VALUE_MATCH_M = 0.001
"""m; the broadcast translation must equal the parameter's (x, y) this closely."""


@dataclass(slots=True)
class _Worst:
    """The worst of a stream of measurements, with its time."""

    count: int = 0
    worst: float = -1.0
    worst_ns: int | None = None
    first_ns: int | None = None
    problem: str = ""

    def add(self, value: float, t_ns: int, problem: str = "") -> None:
        self.count += 1
        if self.first_ns is None:
            self.first_ns = t_ns
        if not math.isfinite(value):  # NaN compares false with everything: it is the worst
            value, problem = math.inf, problem or "not a finite number"
        if value > self.worst:
            self.worst, self.worst_ns = value, t_ns
            if problem:
                self.problem = problem


def _line(
    cid: str,
    description: str,
    passed: bool,
    measured: str,
    threshold: str,
    evidence_ns: int | None,
    detail: str = "",
) -> Check:
    """A rubric line worth :data:`POINTS` ``[cid]``: all of them when it passed, none otherwise."""
    pts = POINTS[cid]
    return Check(
        cid,
        description,
        passed,
        pts if passed else 0.0,
        pts,
        measured,
        threshold,
        evidence_ns,
        detail,
    )


class Grader:
    """Feeds on a ``ros2-final`` log's messages in log order; :meth:`report` gives the rubric."""

    def __init__(self, scenario: Scenario, thresholds: Thresholds | None = None) -> None:
        self.scenario = scenario
        self.th = thresholds or Thresholds()
        self.task = task_of(scenario)
        self.truth_destination = self.task.destination
        self.buffer = BufferCore(cache_time=30.0)
        self.listener = BufferFeeder(self.buffer)
        self._odom: dict[int, tuple[float, float, float]] = {}
        self.odom_tf = _Worst()
        self.target_ns: int | None = None
        self.target_closest = math.inf
        self.detected_ns: int | None = None
        self.detected_ids: list[int] = []
        self.marker_messages = 0
        """Messages on ``/aruco_markers`` (0: the detector never published)."""
        self.first_destination: tuple[float, float, str, int] | None = None
        self.destination_tf = _Worst()
        self.reached_ns: int | None = None
        self.destination_closest = math.inf
        self.destination_closest_ns: int | None = None
        self.start_ns: int | None = None
        self.end_ns = 0

    # -- feeding ------------------------------------------------------------------------------

    def feed(self, topic: str, msg: msgs.Message | None, t_ns: int) -> None:
        """One message of the log (``msg`` None for types the grader does not read)."""
        if self.start_ns is None:
            self.start_ns = t_ns
        self.end_ns = max(self.end_ns, t_ns)
        if msg is None:
            return
        if topic == contract.TF_STATIC and isinstance(msg, msgs.TFMessage):
            self.listener.on_tf_static(msg)
        elif topic == contract.TF and isinstance(msg, msgs.TFMessage):
            self.listener.on_tf(msg)
            for tf in msg.transforms:
                child = tf.child_frame_id.lstrip("/")
                if child == contract.ROS2_BASE_FRAME:
                    self._on_base(tf, t_ns)
                elif child == contract.FINAL_DESTINATION_FRAME:
                    self._on_destination(tf, t_ns)
        elif topic == ODOM and isinstance(msg, msgs.Odometry):
            p = msg.pose.pose
            self._odom[msg.header.stamp.ns] = (
                p.position.x,
                p.position.y,
                yaw_from_quat(p.orientation),
            )
            while len(self._odom) > ODOM_MEMORY:
                del self._odom[next(iter(self._odom))]
        elif topic == TRUTH and isinstance(msg, msgs.PoseStamped):
            self._on_truth((msg.pose.position.x, msg.pose.position.y), t_ns)
        elif topic == contract.ARUCO_MARKERS and isinstance(msg, msgs.ArucoMarkers):
            self.marker_messages += 1
            for mid in msg.marker_ids:
                if mid not in self.detected_ids:
                    self.detected_ids.append(int(mid))
            if (
                self.detected_ns is None
                and self.target_ns is not None
                and self.task.marker_id in msg.marker_ids
            ):
                self.detected_ns = t_ns

    def feed_all(self, items: Iterable[tuple[str, msgs.Message | None, int]]) -> None:
        for topic, msg, t in items:
            self.feed(topic, msg, t)

    def _on_truth(self, xy: tuple[float, float], t_ns: int) -> None:
        d = math.dist(xy, self.task.aruco_target)
        self.target_closest = min(self.target_closest, d)
        if self.target_ns is None and d <= self.th.target_reached_m:
            self.target_ns = t_ns
        if self.detected_ns is not None:
            d = math.dist(xy, self.truth_destination)
            if d < self.destination_closest:
                self.destination_closest, self.destination_closest_ns = d, t_ns
            if self.reached_ns is None and d <= self.th.target_reached_m:
                self.reached_ns = t_ns

    def _on_base(self, tf: msgs.TransformStamped, t_ns: int) -> None:
        parent = tf.header.frame_id.lstrip("/")
        odom = self._odom.get(tf.header.stamp.ns)
        if parent != contract.ROS2_ODOM_FRAME:
            self.odom_tf.add(math.inf, t_ns, f"parent {parent!r}, not {contract.ROS2_ODOM_FRAME}")
            return
        if odom is None:
            self.odom_tf.add(math.inf, t_ns, "stamped with no odometry's stamp")
            return
        tr = tf.transform.translation
        d = math.dist((tr.x, tr.y), odom[:2])
        dyaw = abs(wrap_angle(yaw_from_quat(tf.transform.rotation) - odom[2]))
        off = d if dyaw <= ODOM_MATCH_RAD else math.inf
        self.odom_tf.add(off, t_ns, f"{d * 100:.1f} cm, {math.degrees(dyaw):.1f} deg off odometry")

    def _on_destination(self, tf: msgs.TransformStamped, t_ns: int) -> None:
        tr = tf.transform.translation
        parent = tf.header.frame_id.lstrip("/")
        if self.first_destination is None:
            self.first_destination = (tr.x, tr.y, parent, t_ns)
        if parent != self.task.frame_id:
            self.destination_tf.add(math.inf, t_ns, f"parent {parent!r}")
            return
        try:
            in_map = self.buffer.lookup_transform(
                contract.MAP, contract.FINAL_DESTINATION_FRAME, tf.header.stamp
            )
        except TransformException as err:
            self.destination_tf.add(math.inf, t_ns, f"not in map: {err}")
            return
        p = in_map.transform.translation
        self.destination_tf.add(math.dist((p.x, p.y), self.truth_destination), t_ns)

    # -- verdict ------------------------------------------------------------------------------

    def found_markers(self) -> tuple[FoundMarker, ...]:
        """The project's one marker, once ``marker.detected`` holds (its ID on
        ``/aruco_markers`` after reaching ``aruco_target``); the project never says where it
        is, so no error."""
        if self.detected_ns is None:
            return ()
        when = f"{self.detected_ns / 1e9:.1f} s"  # sim time, as the rubric lines say it
        text = f"detected on {contract.ARUCO_MARKERS} at aruco_target, at {when}"
        return (FoundMarker(self.task.marker_id, text),)

    def report(
        self, source: str, *, log_complete: bool = True, log_problem: str = ""
    ) -> GradeReport:
        """The rubric as judged from what was fed so far (a truncated log: as far as it goes):
        one line per phase of the project, in the table's order."""
        checks = (
            self._odom_to_base(),
            self._aruco_target_reached(),
            self._marker_detected(),
            self._destination_chosen(),
            self._final_destination_broadcast(),
            self._destination_reached(),
            self._time_limit(),
        )
        return GradeReport(
            source,
            checks,
            self.start_ns or 0,
            log_complete,
            log_problem,
            rubric="ros2-final",
            rubric_version=RUBRIC.version,
        )

    def _odom_to_base(self) -> Check:
        """``tf.odom_to_base``: the odometry broadcaster connected the tree, matching odometry."""
        o = self.odom_tf
        if o.count == 0:
            measured, detail = "never broadcast", "nothing connects robot1/odom to base_footprint"
        elif math.isinf(o.worst):
            measured, detail = f"{o.count} broadcasts", f"worst: {o.problem}"
        else:
            measured, detail = f"worst {o.worst * 100:.2f} cm off odometry", ""
        return _line(
            "tf.odom_to_base",
            f"{contract.ROS2_ODOM_FRAME} -> {contract.ROS2_BASE_FRAME} broadcast from odometry",
            o.count > 0 and o.worst <= ODOM_MATCH_M,
            measured,
            f"<= {ODOM_MATCH_M * 100:g} cm, {math.degrees(ODOM_MATCH_RAD):.1f} deg",
            o.worst_ns if o.count and o.worst > ODOM_MATCH_M else o.first_ns,
            detail,
        )

    def _aruco_target_reached(self) -> Check:
        """``aruco_target.reached``: the robot's true pose came near the first goal."""
        tx, ty = self.task.aruco_target
        return _line(
            "aruco_target.reached",
            f"reach aruco_target ({tx:.3f}, {ty:.3f})",
            self.target_ns is not None,
            "reached" if self.target_ns is not None else f"closest {self.target_closest:.3f} m",
            f"<= {self.th.target_reached_m:g} m",
            self.target_ns,
        )

    def _marker_detected(self) -> Check:
        """``marker.detected``: the world's marker ID on ``/aruco_markers`` after the goal."""
        task = self.task
        return _line(
            "marker.detected",
            f"detect marker {task.marker_id} on /aruco_markers at aruco_target",
            self.detected_ns is not None,
            "detected"
            if self.detected_ns is not None
            else (
                f"IDs seen: {', '.join(map(str, self.detected_ids))}"
                if self.detected_ids
                else "never detected"
                if self.marker_messages
                else NO_DETECTOR
            ),
            f"ID {task.marker_id} after reaching aruco_target",
            self.detected_ns,
        )

    def _destination_chosen(self) -> Check:
        """``destination.chosen``: the first broadcast carries the detected ID's parameters."""
        task = self.task
        want = task.destinations[task.marker_id]
        first = self.first_destination
        if first is None:
            chosen, measured_c = False, "no final_destination broadcast"
        else:
            chosen = math.dist(first[:2], want) <= VALUE_MATCH_M
            which = [
                k for k, v in task.destinations.items() if math.dist(first[:2], v) <= VALUE_MATCH_M
            ]
            measured_c = f"({first[0]:.3f}, {first[1]:.3f})" + (
                f" = aruco_{which[0]}" if which else ""
            )
        return _line(
            "destination.chosen",
            f"final_destination.aruco_{task.marker_id} chosen for marker {task.marker_id}",
            chosen,
            measured_c,
            f"({want[0]:g}, {want[1]:g})",
            None if first is None else first[3],
        )

    def _final_destination_broadcast(self) -> Check:
        """``final_destination.broadcast``: every broadcast, looked up in ``map``, is near the
        true destination and a child of the parameter's frame."""
        th, task = self.th, self.task
        d = self.destination_tf
        dx, dy = self.truth_destination
        if d.count == 0:
            measured_b = "never broadcast"
        elif math.isinf(d.worst):
            measured_b = f"worst: {d.problem}"
        else:
            measured_b = f"worst {d.worst:.3f} m from the truth"
        return _line(
            "final_destination.broadcast",
            f"final_destination in {task.frame_id}, at ({dx:.3f}, {dy:.3f}) in map",
            d.count > 0 and d.worst <= th.marker_map_error_m,
            measured_b,
            f"<= {th.marker_map_error_m:g} m, parent {task.frame_id}",
            d.worst_ns if d.count else None,
        )

    def _destination_reached(self) -> Check:
        """``destination.reached``: after the detection, the robot came near the destination."""
        dx, dy = self.truth_destination
        reached = self.reached_ns
        return _line(
            "destination.reached",
            f"reach the final destination ({dx:.3f}, {dy:.3f})",
            reached is not None,
            "reached"
            if reached is not None
            else (
                f"closest {self.destination_closest:.3f} m"
                if self.destination_closest_ns is not None
                else "never went for it"
            ),
            f"<= {self.th.target_reached_m:g} m",
            reached if reached is not None else self.destination_closest_ns,
        )

    def _time_limit(self) -> Check:
        """``time_limit``: the destination was reached within the scenario's time limit."""
        t0 = self.start_ns or 0
        reached = self.reached_ns
        limit_ns = t0 + int(self.scenario.time_limit_s * 1e9)
        in_time = reached is not None and reached <= limit_ns
        return _line(
            "time_limit",
            f"final destination reached within {self.scenario.time_limit_s:g} s",
            in_time,
            "not reached" if reached is None else f"{(reached - t0) / 1e9:.1f} s",
            f"<= {self.scenario.time_limit_s:g} s",
            reached,
        )


RUBRIC = Rubric(Grader, GRADE_TOPICS, REQUIRED_TOPICS, trusted_topics=(contract.ARUCO_MARKERS,))
"""The ROS 2 final project rubric, as its assignment carries it."""
