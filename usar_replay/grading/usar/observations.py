"""What the rubric observes in a log: a streaming consumer with bounded state.

Why apart from the lines: the observing is the hard part (tf2's rules for broadcasts, stops,
detection windows, bounded memory on a hostile log); the lines (one module per section-9
question) only turn what was kept into verdicts. :meth:`Observations.feed` takes one message at
a time, in log order: entry times into a disc around each target, marker and home (a follower's
counting only when it stopped), detections and whether the explorer was at a target then, the
frames broadcast on ``/tf`` placed in ``map`` with the tf2 rules the mission uses, and when the
follower first moved. Robots are judged by the simulator's ground truth, never by what the
mission believes.
"""

from __future__ import annotations

import bisect
import math
from collections import deque
from collections.abc import Iterable
from dataclasses import dataclass, field, replace

from usar_replay.core import contract, msgs
from usar_replay.core.finite import nonfinite_field
from usar_replay.core.safe_text import safe_line
from usar_replay.core.settings import Thresholds
from usar_replay.core.tf_tree import BufferCore, BufferFeeder, TransformException
from usar_replay.grading.usar.follow import FrameFollow, rotate, sample
from usar_replay.grading.usar.rules import (
    BROADCAST_MATCH_M,
    FOLLOW_MATCH_M,
    MAX_GOAL_TOLERANCE_M,
    SCAN_TURN_RAD_S,
    TEMPLATE_GOAL_TOLERANCE_M,
)
from usar_replay.world.scenario import Scenario

__all__ = [
    "DETECTION_MEMORY_NS",
    "GRADE_TOPICS",
    "MAX_FRAMES",
    "MAX_SAMPLES",
    "MAX_VISITS",
    "NO_DETECTOR",
    "OTHER_FRAMES",
    "REQUIRED_TOPICS",
    "Broadcasts",
    "Disc",
    "FrameBroadcasts",
    "Observations",
]

EXPLORER_TRUTH = contract.truth_pose("explorer")
FOLLOWER_TRUTH = contract.truth_pose("follower")
GRADE_TOPICS = (
    contract.TF_STATIC,
    contract.TF,
    contract.FIDUCIALS,
    EXPLORER_TRUTH,
    FOLLOWER_TRUTH,
    *(contract.cmd_vel(r) for r in contract.ROBOTS),
)
"""The topics the rubric reads; everything else in a log is skipped without decoding."""
REQUIRED_TOPICS = (EXPLORER_TRUTH, FOLLOWER_TRUTH, contract.TF)
"""Without these a log cannot be graded at all: the simulator writes them from the first tick
(ground truth, and ``/tf`` for its odom links), so a complete log without one is not a log of a
run. Every topic the mission writes is optional: a mission that never started the detector
node has no ``/fiducial_transforms``, and is graded (its detection lines fail with
:data:`NO_DETECTOR`). ``/tf_static`` may be absent too: a world whose chain is all dynamic is
still gradable."""
NO_DETECTOR = (
    f"no {contract.FIDUCIALS} in the log: did the mission start the detector node (ArucoDetect)?"
)
"""What the detection lines measure when the detector never published (a mission without
``ArucoDetect()`` in its ``main()``)."""
MAX_SAMPLES = 1024
"""Broadcast places kept per frame for its median (the latest; a ring, so memory stays flat)."""
MAX_VISITS = 256
"""Entry times kept per disc; past this the newest replaces the last kept (the bound only keeps
memory flat on a pathological log)."""
MAX_FRAMES = 16
"""Broadcast frame names kept apart; past this, a new name counts as :data:`OTHER_FRAMES` (the
bound only keeps memory flat on a log that broadcasts a new name every tick)."""
OTHER_FRAMES = "(other frames)"
DETECTION_MEMORY_NS = 30 * 1_000_000_000
"""The grader's tf cache time: a broadcast whose parent's transform is older than that cannot
be looked up in ``map``."""


@dataclass(slots=True)
class Disc:
    """One robot's visits to one place: the times it entered a disc around it.

    ``count_start``: whether being inside at the first sample counts as an arrival (a target
    yes; home no: a robot is home only once it has left it and come back).
    """

    centre: tuple[float, float]
    radius: float
    leave: float
    count_start: bool
    inside: bool | None = None
    entries: list[int] = field(default_factory=list)
    stay_closest: list[float] = field(default_factory=list)
    """Closest distance during each stay, parallel to :attr:`entries`."""
    closest_m: float = math.inf
    closest_ns: int | None = None
    first_ns: int | None = None
    last_m: float = math.inf
    """Distance at the latest sample (where the robot ended, at the end of the log)."""

    def update(self, xy: tuple[float, float], t_ns: int, *, counts: bool = True) -> None:
        """One sample; ``counts`` False: inside the disc is not an arrival now (the robot is
        moving, and only a stop is a visit)."""
        d = math.dist(xy, self.centre)
        self.last_m = d
        if self.first_ns is None:
            self.first_ns = t_ns
        if d < self.closest_m:
            self.closest_m, self.closest_ns = d, t_ns
        if d <= self.radius and (counts or self.inside):
            if self.inside is False or (self.inside is None and self.count_start):
                if len(self.entries) < MAX_VISITS:
                    self.entries.append(t_ns)
                    self.stay_closest.append(d)
                else:
                    self.entries[-1], self.stay_closest[-1] = t_ns, d
            elif self.inside and self.stay_closest:
                self.stay_closest[-1] = min(self.stay_closest[-1], d)
            self.inside = True
        elif self.inside is None or d > self.leave:
            self.inside = False

    def first_after(self, t_ns: int) -> int | None:
        """The first arrival strictly after ``t_ns`` (entries are in time order)."""
        i = bisect.bisect_right(self.entries, t_ns)
        return self.entries[i] if i < len(self.entries) else None

    def stay_at(self, t_ns: int) -> float:
        """The closest distance during the stay that began at ``t_ns``."""
        return self.stay_closest[bisect.bisect_left(self.entries, t_ns)]

    def closest_evidence(self) -> int | None:
        """When the robot came closest, unless that was where it started (nothing happened)."""
        return None if self.closest_ns == self.first_ns else self.closest_ns


@dataclass(slots=True)
class FrameBroadcasts:
    """One child frame's broadcasts attributed to one marker (a TA's look at that frame)."""

    frame: str
    count: int = 0
    worst_m: float = -1.0
    worst_ns: int = 0
    worst_stamp: tuple[int, int] = (0, 0)
    """(the broadcast's stamp, the detection's image stamp) of the worst one."""
    first_ns: int | None = None
    first_stamp: tuple[int, int] = (0, 0)
    failed_lookups: int = 0
    at_target: list[tuple[tuple[float, float, float], tuple[float, float]]] = field(
        default_factory=list
    )
    """(place in ``map``, the explorer's position) of the broadcasts made while the explorer
    was at a target, of a detection within the reliable range: what a TA sees in RViz (the
    latest :data:`MAX_SAMPLES`)."""
    at_target_count: int = 0
    elsewhere: list[tuple[tuple[float, float, float], tuple[float, float]]] = field(
        default_factory=list
    )
    """The same of every other broadcast (driving, or from far away): judged only when no
    frame of the marker was broadcast at a target."""
    elsewhere_count: int = 0
    _last: tuple[int, bool, int] | None = None
    """(stamp, deciding, index) of the latest sample kept."""

    def keep(
        self,
        place: tuple[float, float, float],
        explorer: tuple[float, float],
        deciding: bool,
        stamp: int,
    ) -> None:
        """One finite broadcast's place, stamped ``stamp``, in the ring it belongs to. A second
        broadcast of the frame at the stamp of the one before replaces it: tf keeps the last
        one inserted at a stamp, and that is what RViz shows (team 001's identity broadcast
        right after the right one)."""
        ring = self.at_target if deciding else self.elsewhere
        if self._last is not None and self._last[:2] == (stamp, deciding):
            ring[self._last[2]] = (place, explorer)
            return
        n = self.at_target_count if deciding else self.elsewhere_count
        if len(ring) < MAX_SAMPLES:
            ring.append((place, explorer))
            index = len(ring) - 1
        else:
            index = n % MAX_SAMPLES
            ring[index] = (place, explorer)
        self._last = (stamp, deciding, index)
        if deciding:
            self.at_target_count += 1
        else:
            self.elsewhere_count += 1


@dataclass(slots=True)
class Broadcasts:
    """The broadcasts attributed to one marker: only those made within ``detection_recent_s``
    after a detection of it (a broadcast without one is no evidence of a detection;
    ``only_on_detection`` judges it), by child frame name."""

    frames: dict[str, FrameBroadcasts] = field(default_factory=dict)


class Observations:
    """Observes a log's messages in log order (the rubric's lines judge what it kept;
    :class:`~usar_replay.grading.usar.judge.Grader` adds the report)."""

    def __init__(self, scenario: Scenario, thresholds: Thresholds | None = None) -> None:
        self.scenario = scenario
        self.th = th = thresholds or Thresholds()
        self.targets = [(float(t[0]), float(t[1])) for t in scenario.targets]
        self.markers = {m.id: (m.x, m.y, m.z) for m in sorted(scenario.markers, key=lambda m: m.id)}
        self.marker_yaw = {m.id: m.yaw for m in scenario.markers}
        """Which way each marker's face points (its +x): a stand-off frame is in front of it."""
        self.explorer_home = (scenario.explorer.x, scenario.explorer.y)
        self.follower_home = (scenario.follower.x, scenario.follower.y)
        self.buffer = BufferCore(cache_time=DETECTION_MEMORY_NS / 1e9)
        self.listener = BufferFeeder(self.buffer)

        def disc(c: tuple[float, float], r: float, count_start: bool) -> Disc:
            return Disc(c, r, r + th.reentry_m, count_start)

        def tolerance(value: float | None) -> float:
            # what the package's move_base may widen the rubric by: at most the handout's
            # 0.4 m (rules.MAX_GOAL_TOLERANCE_M), however far its robot is let stop short
            own = TEMPLATE_GOAL_TOLERANCE_M if value is None else value
            return min(own, MAX_GOAL_TOLERANCE_M)

        self.explorer_tolerance = tolerance(th.explorer_goal_tolerance_m)
        self.follower_tolerance = tolerance(th.follower_goal_tolerance_m)
        own = self.explorer_tolerance + th.goal_slack_m
        self.target_radius = own if own > th.target_reached_m + 1e-9 else th.target_reached_m
        """How near a target the explorer must come: v2's 0.15 m, or the package's own goal
        tolerance (at most the handout's 0.4 m) plus the controller's overshoot where that is
        more."""
        self.visit_radius = (
            math.sqrt(2.0) * th.follower_visit_m + self.follower_tolerance + th.goal_slack_m
        )
        """How near a marker the follower must stop: the handout's 0.4 m stand-off in x and
        in y, the package's goal tolerance (at most 0.4 m), the overshoot (0.72 m with the
        template's, 1.07 m at most)."""
        self.stand_off_m = math.sqrt(2.0) * th.follower_visit_m + th.marker_map_error_m
        """The farthest a stand-off frame may be from its marker: the follower's stand-off in
        x and y plus the broadcast threshold."""
        self.target_discs = [disc(t, self.target_radius, True) for t in self.targets]
        self.explorer_home_disc = disc(self.explorer_home, th.home_m, False)
        self.marker_discs = {
            k: disc(v[:2], self.visit_radius, True) for k, v in self.markers.items()
        }
        self.explorer_xy: tuple[float, float] | None = None
        self._explorer_yaw: tuple[int, float] | None = None
        self.explorer_turning_fast = False
        """Turning faster than :data:`SCAN_TURN_RAD_S` (move_base turning to its next goal,
        not the scan's slow spin): a frame stamped "now" then is off by the turn since its
        image, and a TA looks at the frame while the explorer scans."""
        self.explorer_at_target = False
        """The explorer's true position is within :attr:`target_radius` of a target (stopped
        there or turning there: where it looks for a marker)."""
        self._trail: deque[tuple[int, tuple[float, float]]] = deque()
        """The follower's recent true positions, for whether it has stopped."""
        self.follower_stops = 0
        self.follower_home_disc = disc(self.follower_home, th.home_m, False)
        self.follower_start: tuple[float, float] | None = None
        self.follower_moved_ns: int | None = None
        self.detected_ns: dict[int, int] = {}
        self.detected_frames: dict[int, int] = {}
        """Frames in which the detector saw a marker while the explorer was at a target."""
        self.glimpsed_ns: dict[int, int] = {}
        self.glimpsed_frames: dict[int, int] = {}
        """The same anywhere else (driving past): not a detection the mission could use."""
        self.recent_ns = int(th.detection_recent_s * 1e9)
        self._detections: deque[tuple[int, int, tuple[msgs.FiducialTransform, ...]]] = deque()
        """(arrival, image stamp, transforms) of the non-empty detections of the last
        :attr:`recent_ns`."""
        self.last_fiducials_empty = False
        """The latest ``/fiducial_transforms`` held nothing (the marker out of view)."""
        self._sent: dict[str, set[tuple[int, int]]] = {}
        self.frame_tally: dict[str, list[int]] = {}
        """Per frame name, [broadcasts on a detection, broadcasts without one]: a frame sent
        mostly without one (a timer's, the template's dummy ``my_frame``) is not a detection's
        (:func:`usar_replay.grading.usar.broadcast.frame_places`)."""
        self._frame_marker: dict[str, int] = {}
        """The marker each frame name was last broadcast as (a detection's)."""
        """Per frame, the detections (image stamp, ID) it was broadcast as, the recent ones."""
        self.detections_read: bool | None = None
        """Whether a node of the mission subscribed to the detections: a ROS 1 package's node
        subscribed to ``/fiducial_transforms`` (the log's ``ros1.toml``); None: not known (a
        Python mission, whose nodes read them in its own process, or an older log). Where
        True, the package read them only where one of its frames follows them
        (:meth:`detections_followed`)."""
        self.follow: dict[str, FrameFollow] = {}
        """Per frame name, how its broadcasts sat to the detections they were sent on
        (:mod:`.follow`)."""
        self.fiducial_messages = 0
        """Messages on ``/fiducial_transforms``, empty ones included (0: no detector ran)."""
        self._not_candidates = frozenset((contract.MAP, *contract.sim_frames()))
        self.broadcasts: dict[int, Broadcasts] = {k: Broadcasts() for k in self.markers}
        self.broadcast_count = 0
        self.broadcast_frames: dict[str, int] = {}
        """Broadcasts by child frame name, in the order first seen."""
        self.without_detection = 0
        self.without_detection_ns: int | None = None
        self.without_detection_what = ""
        self.wrong_parent = 0
        self.wrong_parent_ns: int | None = None
        self.wrong_parent_what = ""
        self.bad_broadcasts = 0
        """Broadcasts without a detection *or* with another parent (each counted once)."""
        self.start_ns: int | None = None
        self.end_ns = 0
        self._cmd_tick: dict[str, tuple[int, set[tuple[float, ...]]]] = {}
        self.cmd_conflicts: dict[str, int] = {r: 0 for r in contract.ROBOTS}
        self.cmd_conflict_ns: dict[str, int | None] = {r: None for r in contract.ROBOTS}

    def feed(self, topic: str, msg: msgs.Message | None, t_ns: int) -> None:
        """One message of the log (``msg`` None for types the grader does not read)."""
        if self.start_ns is None:
            self.start_ns = t_ns
        self.end_ns = max(self.end_ns, t_ns)
        if msg is None:
            return
        if topic == contract.TF and isinstance(msg, msgs.TFMessage):
            self.listener.on_tf(msg)
            self._on_broadcasts(msg, t_ns)
        elif topic == EXPLORER_TRUTH and isinstance(msg, msgs.PoseStamped):
            xy = (msg.pose.position.x, msg.pose.position.y)
            for d in self.target_discs:
                d.update(xy, t_ns)
            self.explorer_home_disc.update(xy, t_ns)
            self.explorer_xy = xy
            self._explorer_turn(msg.pose.orientation, t_ns)
            self.explorer_at_target = any(
                math.dist(xy, c) <= self.target_radius for c in self.targets
            )
        elif topic == FOLLOWER_TRUTH and isinstance(msg, msgs.PoseStamped):
            self._on_follower((msg.pose.position.x, msg.pose.position.y), t_ns)
        elif topic == contract.FIDUCIALS and isinstance(msg, msgs.FiducialTransformArray):
            self._on_fiducials(msg, t_ns)
        elif topic == contract.TF_STATIC and isinstance(msg, msgs.TFMessage):
            self.listener.on_tf_static(msg)
        elif isinstance(msg, msgs.Twist):
            robot = contract.robot_of_topic(topic)
            if robot is not None and topic == contract.cmd_vel(robot):
                self._on_cmd_vel(robot, msg, t_ns)

    def _on_cmd_vel(self, robot: str, msg: msgs.Twist, t_ns: int) -> None:
        """Two different moving commands for one robot in one tick: two publishers fight (a
        spin timer and the navigator, say); the robot obeys whichever came last. A stop after
        a command is a node ending its goal, not a fight."""
        lin, ang = msg.linear, msg.angular
        cmd = (lin.x, lin.y, lin.z, ang.x, ang.y, ang.z)
        if not any(cmd):
            return
        t, seen = self._cmd_tick.get(robot, (-1, set()))
        if t != t_ns:
            self._cmd_tick[robot] = (t_ns, {cmd})
            return
        if cmd not in seen and len(seen) == 1:
            self.cmd_conflicts[robot] += 1
            if self.cmd_conflict_ns[robot] is None:
                self.cmd_conflict_ns[robot] = t_ns
        seen.add(cmd)

    def feed_all(self, items: Iterable[tuple[str, msgs.Message | None, int]]) -> None:
        for topic, msg, t in items:
            self.feed(topic, msg, t)

    def _on_fiducials(self, msg: msgs.FiducialTransformArray, t_ns: int) -> None:
        self.fiducial_messages += 1
        if any(nonfinite_field(f) for f in msg.transforms):
            # a detection at NaN or infinity is no detection (the course's detector never
            # publishes one; the recorder refuses it from a mission)
            msg = msgs.FiducialTransformArray(
                header=msg.header,
                transforms=tuple(f for f in msg.transforms if not nonfinite_field(f)),
            )
        seen_ns, frames = (
            (self.detected_ns, self.detected_frames)
            if self.explorer_at_target
            else (self.glimpsed_ns, self.glimpsed_frames)
        )
        for f in msg.transforms:
            seen_ns.setdefault(f.fiducial_id, t_ns)
            frames[f.fiducial_id] = frames.get(f.fiducial_id, 0) + 1
        self.last_fiducials_empty = not msg.transforms
        if msg.transforms:
            self._detections.append((t_ns, msg.header.stamp.ns, msg.transforms))
        while self._detections and self._detections[0][0] < t_ns - self.recent_ns:
            self._detections.popleft()

    def _on_follower(self, xy: tuple[float, float], t_ns: int) -> None:
        if self.follower_start is None:
            self.follower_start = xy
        if (
            self.follower_moved_ns is None
            and math.dist(xy, self.follower_start) > self.th.follower_moved_m
        ):
            self.follower_moved_ns = t_ns
        stopped = self._stopped(xy, t_ns)
        for d in self.marker_discs.values():
            d.update(xy, t_ns, counts=stopped)
        self.follower_home_disc.update(xy, t_ns)

    def _explorer_turn(self, q: msgs.Quaternion, t_ns: int) -> None:
        """The explorer's turn rate between its last two true poses."""
        yaw = math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))
        last = self._explorer_yaw
        self._explorer_yaw = (t_ns, yaw)
        if last is None or t_ns <= last[0]:
            return
        turn = math.remainder(yaw - last[1], math.tau)
        self.explorer_turning_fast = abs(turn) / ((t_ns - last[0]) / 1e9) > SCAN_TURN_RAD_S

    def _stopped(self, xy: tuple[float, float], t_ns: int) -> bool:
        """Has the follower stayed within ``stopped_m`` of ``xy`` for ``stopped_s``? (a goal
        reached and the turn to the next: a stop; a drive-by: not)."""
        trail, window = self._trail, int(self.th.stopped_s * 1e9)
        trail.append((t_ns, xy))
        while len(trail) > 1 and (trail[1][0] <= t_ns - window or len(trail) > MAX_SAMPLES):
            trail.popleft()
        still = trail[0][0] <= t_ns - window and all(
            math.dist(p, xy) <= self.th.stopped_m for _, p in trail
        )
        self.follower_stops += still
        return still

    def _on_broadcasts(self, msg: msgs.TFMessage, t_ns: int) -> None:
        """The broadcasts of one ``/tf`` message: every transform whose child is not one of the
        simulator's frames (any name: ``marker_frame``, ``my_frame``, ``target_1``), judged
        after the message is in the buffer (as tf2 sees it). Work is linear in the *distinct*
        broadcasts: identical ones are judged once and counted as often as they were sent, and
        a parent is looked up in ``map`` once per stamp (the buffer does not change within the
        message), so a message with thousands of copies (a grade bomb) costs one judgement."""
        sent: dict[msgs.TransformStamped, int] = {}
        for tf in msg.transforms:
            if tf.child_frame_id.lstrip("/") not in self._not_candidates:
                sent[tf] = sent.get(tf, 0) + 1
        parents: dict[tuple[str, int], msgs.TransformStamped | None] = {}
        for tf, times in sent.items():
            # ros::Time(0) (the sample code's lookup time, used as a stamp) means "now": the
            # frame as it was when it was published
            stamp = tf.header.stamp.ns or t_ns
            key = (tf.header.frame_id, stamp)
            if key not in parents:
                try:
                    parents[key] = self.buffer.lookup_transform(contract.MAP, key[0], stamp)
                except TransformException:
                    parents[key] = None
            parent = parents[key]
            where = None if parent is None else _compose(parent.transform, tf.transform)
            self._on_broadcast(tf, stamp, t_ns, times, where, parent)

    def _window(self, t_ns: int) -> list[tuple[int, msgs.FiducialTransform]]:
        """The detections a broadcast sent at ``t_ns`` may be: (image stamp, detection) of
        those that came within ``detection_recent_s`` before it, newest first (a package that
        drains a queue of detections broadcasts each one late: still a detection's)."""
        return [
            (stamp, f)
            for came, stamp, found in reversed(self._detections)
            if t_ns - self.recent_ns <= came <= t_ns
            for f in found
        ]

    def _on_broadcast(
        self,
        tf: msgs.TransformStamped,
        stamp: int,
        t_ns: int,
        times: int,
        where: tuple[float, float, float] | None,
        parent: msgs.TransformStamped | None = None,
    ) -> None:
        """``times`` identical broadcasts of ``tf``, stamped ``stamp`` (its own, or the log time
        for a zero stamp); ``where`` is its child frame's position in ``map`` through its
        ``parent`` at that stamp (None: the parent could not be looked up)."""
        frame = _frame_name(tf.child_frame_id)
        if frame not in self.broadcast_frames and len(self.broadcast_frames) >= MAX_FRAMES:
            frame = OTHER_FRAMES
        what = f"{frame} stamped {stamp / 1e9:.3f} s"
        self.broadcast_count += times
        self.broadcast_frames[frame] = self.broadcast_frames.get(frame, 0) + times
        on_camera = tf.header.frame_id.lstrip("/") == contract.OPTICAL_FRAME
        if not on_camera:
            self.wrong_parent += times
            if self.wrong_parent_ns is None:
                self.wrong_parent_ns, self.wrong_parent_what = t_ns, what
        window = self._window(t_ns)
        sent = self._sent.setdefault(frame, set())
        copied, again = self._copied(tf, window, sent) if on_camera else (None, False)
        if copied is not None:
            if len(sent) >= MAX_SAMPLES:
                sent.clear()  # memory stays flat; a later copy counts as new
            sent.add(copied)
        # no detection came recently, or the marker is out of view now and this is no
        # detection's first broadcast (a stored pose sent again: the handout's "broadcast only
        # when the marker is detected")
        alone = not window or (self.last_fiducials_empty and (copied is None or again))
        tally = self.frame_tally.setdefault(frame, [0, 0])
        tally[1 if alone else 0] += times
        if alone:
            self.without_detection += times
            if self.without_detection_ns is None:
                self.without_detection_ns, self.without_detection_what = t_ns, what
            self.bad_broadcasts += times
        elif not on_camera:
            self.bad_broadcasts += times
        if alone:
            # no detection to be the broadcast of; a frame that was a marker's shows in RViz
            # where the marker is not (a stored pose sent again "follows the robot around")
            known = self._frame_marker.get(frame)
            if known is not None and where is not None and all(map(math.isfinite, where)):
                b = self.broadcasts[known].frames[frame]
                b.keep(where, self.explorer_xy or self.explorer_home, True, stamp)
            return
        image, found = self._attribute(tf, window, where, on_camera)
        mid = found.fiducial_id
        if mid not in self.markers:
            return
        self._frame_marker[frame] = mid
        self._keep_follow(frame, tf, stamp, where, found, parent if on_camera else None)
        b = self.broadcasts[mid].frames.setdefault(frame, FrameBroadcasts(frame))
        b.count += times
        if b.first_ns is None:
            b.first_ns, b.first_stamp = t_ns, (stamp, image)
        err = math.inf if where is None else math.dist(where, self.markers[mid])
        if not math.isfinite(err):  # NaN is never "worse than" anything: make it the worst
            b.failed_lookups += times
            err = math.inf
        if err > b.worst_m:
            b.worst_m, b.worst_ns, b.worst_stamp = err, t_ns, (stamp, image)
        if where is not None and math.isfinite(err):
            v = found.transform.translation
            near = math.sqrt(v.x * v.x + v.y * v.y + v.z * v.z) <= self.th.reliable_range_m
            explorer = self.explorer_xy or self.explorer_home
            scanning = self.explorer_at_target and not self.explorer_turning_fast
            b.keep(where, explorer, scanning and near, stamp)

    def _keep_follow(
        self,
        frame: str,
        tf: msgs.TransformStamped,
        stamp: int,
        where: tuple[float, float, float] | None,
        found: msgs.FiducialTransform,
        camera: msgs.TransformStamped | None,
    ) -> None:
        """How this broadcast sits to the detection it is judged as (:mod:`.follow`): its
        origin in the camera frame at its stamp (through ``map`` where its parent is another
        frame), with the camera's rotation in ``map``."""
        if camera is None:
            if where is None:
                return
            try:
                camera = self.buffer.lookup_transform(contract.MAP, contract.OPTICAL_FRAME, stamp)
            except TransformException:
                return
            p = camera.transform.translation
            rel = (where[0] - p.x, where[1] - p.y, where[2] - p.z)
            b = rotate(camera.transform.rotation, rel, inverse=True)
        else:
            v = tf.transform.translation
            b = (v.x, v.y, v.z)
        if not all(map(math.isfinite, b)) or nonfinite_field(found):
            return
        got = sample(b, found.transform, camera.transform.rotation, self.stand_off_m)
        if all(map(math.isfinite, (*got.in_marker, *got.in_map))):
            self.follow.setdefault(frame, FrameFollow()).keep(got)

    def frame_verdict(self, frame: str) -> str:
        """How ``frame`` follows the detections it was sent on (:meth:`.FrameFollow.verdict`:
        ``follows``, ``empty``, ``ignores``, ``moves`` or ``unknown``)."""
        f = self.follow.get(frame)
        return "unknown" if f is None else f.verdict(self.stand_off_m)

    def ignoring_frames(self) -> list[str]:
        """The frames that did not move with the detections they were sent on (a place fixed
        ahead of the camera): no detection's broadcasts (issue 50)."""
        return [f for f in self.follow if self.frame_verdict(f) == "ignores"]

    def detections_followed(self) -> bool:
        """Do the mission's broadcasts follow its detections: a frame sent mostly on them (not
        a timer's) that does not ignore them (a copy, a stand-off, wrong maths on them, the
        empty transform of the detection callback)? Where a ROS 1 package's node subscribed,
        this is what says the package read them (issue 50: a node that only subscribes, or
        that sends a place fixed ahead of the camera, reads nothing)."""
        return any(
            with_one and with_one >= without and self.frame_verdict(frame) != "ignores"
            for frame, (with_one, without) in self.frame_tally.items()
        )

    def _copied(
        self,
        tf: msgs.TransformStamped,
        window: list[tuple[int, msgs.FiducialTransform]],
        sent: set[tuple[int, int]],
    ) -> tuple[tuple[int, int] | None, bool]:
        """(image stamp, ID) of the recent detection this camera-parented broadcast copies
        (within :data:`BROADCAST_MATCH_M`), and whether every such detection was broadcast by
        this frame already (a stored pose sent again). A stopped camera sees the same pose in
        frame after frame, so the copy is the oldest such detection not yet sent: a queue
        drained late sends each once; a package resending its store sends more copies than
        there were detections."""
        near = sorted(
            (s, f.fiducial_id)
            for s, f in window
            if _apart_m(tf.transform, f.transform) <= BROADCAST_MATCH_M
        )
        if not near:
            return None, False
        fresh = next((key for key in near if key not in sent), None)
        return (fresh, False) if fresh is not None else (near[-1], True)

    def _attribute(
        self,
        tf: msgs.TransformStamped,
        window: list[tuple[int, msgs.FiducialTransform]],
        where: tuple[float, float, float] | None,
        on_camera: bool,
    ) -> tuple[int, msgs.FiducialTransform]:
        """(image stamp, detection) a broadcast is: on the camera, the one it copies
        (identical, else within the match), else the one on whose line from the camera it lies
        (a stand-off along the ray), else the nearest in the camera frame; elsewhere, the
        detected marker nearest to where it puts its frame in ``map``."""
        if on_camera:
            exact = next(((s, f) for s, f in window if f.transform == tf.transform), None)
            v = tf.transform.translation
            b = (v.x, v.y, v.z)
            near = min(window, key=lambda sf: _apart_m(tf.transform, sf[1].transform))
            if exact or _apart_m(tf.transform, near[1].transform) <= BROADCAST_MATCH_M:
                return exact or near
            ray = min(window, key=lambda sf: _off_ray(b, sf[1].transform))
            return ray if _off_ray(b, ray[1].transform) <= FOLLOW_MATCH_M else near
        if where is None:
            return window[0]
        known = [(s, f) for s, f in window if f.fiducial_id in self.markers]
        if not known:
            return window[0]
        return min(known, key=lambda sf: math.dist(where, self.markers[sf[1].fiducial_id]))

    def resolved_thresholds(self) -> Thresholds:
        """The thresholds judged by, with the scenario's time limit filled in."""
        if self.th.time_limit_s is not None:
            return self.th
        return replace(self.th, time_limit_s=float(self.scenario.time_limit_s))


def _apart_m(a: msgs.Transform, b: msgs.Transform) -> float:
    """How far apart two transforms put their child frame's origin (metres)."""
    p, q = a.translation, b.translation
    return math.dist((p.x, p.y, p.z), (q.x, q.y, q.z))


def _off_ray(b: tuple[float, float, float], d: msgs.Transform) -> float:
    """How far ``b`` is from the segment camera -> ``d`` (inf behind the camera or past d)."""
    t = d.translation
    dd = t.x * t.x + t.y * t.y + t.z * t.z
    s = (b[0] * t.x + b[1] * t.y + b[2] * t.z) / dd if dd > 0 else -1.0
    if not 0.0 < s <= 1.0:
        return math.inf
    return math.dist(b, (s * t.x, s * t.y, s * t.z))


def _frame_name(frame: str) -> str:
    """A frame name from the mission as a report shows it: control characters escaped, at most
    40 characters (it is the team's text, shown on a TA's terminal)."""
    shown = safe_line(frame)
    return shown if len(shown) <= 40 else shown[:37] + "..."


def _compose(parent: msgs.Transform, child: msgs.Transform) -> tuple[float, float, float]:
    """Where ``child`` (a transform from its parent) puts its frame's origin, given the
    parent's transform in ``map``."""
    q, v, p = parent.rotation, child.translation, parent.translation
    # v' = v + 2w (u x v) + 2 u x (u x v), u the quaternion's vector part
    tx = 2 * (q.y * v.z - q.z * v.y)
    ty = 2 * (q.z * v.x - q.x * v.z)
    tz = 2 * (q.x * v.y - q.y * v.x)
    return (
        p.x + v.x + q.w * tx + (q.y * tz - q.z * ty),
        p.y + v.y + q.w * ty + (q.z * tx - q.x * tz),
        p.z + v.z + q.w * tz + (q.x * ty - q.y * tx),
    )
