"""The course's live-demo rubric (60 points), pure: messages in, verdicts out.

Why pure: the rubric is the part of usar a TA argues about, so it must be readable and testable
on its own, without a log file, mcap or a simulator. This module reads no file and imports no
mcap; :mod:`usar_replay.grading.grade` opens a log and feeds it here, ``usar replay --grade`` feeds
the replayed outputs, and the tests feed hand-made message streams.

Two halves:

* :class:`Grader` (the *observations*): a streaming consumer, :meth:`Grader.feed` one message at
  a time, keeping bounded state: entry times into a disc around each target, marker and home,
  detections, the frames broadcast on ``/tf`` placed in ``map`` with the tf2 rules the mission
  uses, and when the follower first moved;
* one small function per rubric line (:func:`explorer_targets`, :func:`marker_detected`,
  :func:`marker_broadcast`, :func:`only_on_detection`, :func:`explorer_home_before_follower`,
  :func:`follower_markers`, :func:`follower_home`, :func:`time_limit`) turning observations into
  :class:`Check` verdicts, each with its measured value and threshold as numbers with units, and
  the sim time of its evidence.

Robots are judged by the simulator's ground truth, never by what the mission believes.
Broadcasts are judged as a TA looks at frames in RViz (:data:`RUBRIC_VERSION` 2, issue #32): the
assignment says "e.g., marker_frame" and its sample code stamps with ``ros::Time::now()``, so real
packages name the frame ``my_frame`` or ``target_<id>`` and stamp it a tick after the image.

===================================  ======  ===================================================
line (``Check.id``)                  points  passes when
===================================  ======  ===================================================
``explorer.target_k``                12      the explorer came within ``target_reached_m`` of
                                             target_k after the earlier targets it reached
``marker_k.detected``                12      the course's detector's ``/fiducial_transforms``
                                             (trusted; never a mission's) holds ID k once
``marker_k.broadcast``               8       a frame broadcast on ``/tf`` (any name but the
                                             simulator's) within one camera period after the
                                             detection of an image where marker k was seen
                                             (it came with the image, or a tick later where
                                             the detector answers a tick later), every such
                                             broadcast of that frame, placed in ``map``
                                             through its parent at its stamp, within
                                             ``marker_map_error_m`` of the true marker (a
                                             non-finite one is the worst)
``marker_frame.only_on_detection``   4       something was broadcast, and every broadcast is a
                                             child of the camera's optical frame, stamped
                                             within one camera period after a detection
                                             (a zero stamp: when it was sent), and not an
                                             older frame's detection stamped anew ("nothing
                                             broadcast" fails: no credit without evidence)
``explorer.home_before_follower``    4       after its last target the explorer came within
                                             ``home_m`` of its start before the follower moved
``follower.marker_k``                12      the follower came within ``follower_visit_m`` of
                                             marker k after the lower IDs it visited
``follower.home``                    4       after its last in-order marker, the follower came
                                             within ``home_m`` of its start
``time_limit``                       4       the follower was home within the time limit
===================================  ======  ===================================================

Points are scaled per item when a scenario has more or fewer than four targets/markers.

Order is judged once, by :func:`in_order`, as a *subsequence* of arrivals: item k passes when it
was reached after the in-order arrival at the previous reached item (greedily, earliest first).
An explorer that skips target_2 fails only ``explorer.target_2``; one that drives past target_3
on its way to target_1 is not punished; one that visits 2, 1, 3, 4 fails ``explorer.target_2``.
"Home" counts only after the robot has left it and after its last in-order item.
"""

from __future__ import annotations

import bisect
import math
import statistics
from collections import deque
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field, replace

from usar_replay.core import contract, msgs
from usar_replay.core.finite import nonfinite_field
from usar_replay.core.safe_text import safe_line
from usar_replay.core.settings import Thresholds
from usar_replay.core.tf_tree import BufferCore, BufferFeeder, TransformException
from usar_replay.grading.verdict import Check, FoundMarker, GradeReport, Rubric
from usar_replay.world.scenario import Scenario

__all__ = [
    "RUBRIC",
    "RUBRIC_VERSION",
    "DETECTION_MEMORY_NS",
    "GRADE_TOPICS",
    "MAX_FRAMES",
    "MAX_VISITS",
    "NO_DETECTOR",
    "REQUIRED_TOPICS",
    "Disc",
    "Grader",
    "explorer_home_before_follower",
    "explorer_targets",
    "follower_home",
    "follower_markers",
    "in_order",
    "judge",
    "marker_broadcast",
    "marker_detected",
    "one_cmd_vel_publisher",
    "only_on_detection",
    "time_limit",
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
RUBRIC_VERSION = 3
"""1: only ``marker_frame`` was a broadcast, stamped exactly with a detected image's stamp.
2 (issue #32): a frame of any name on ``/tf`` (not the simulator's), stamped within one camera
period after a detected image (or zero: when it was sent), placed in ``map`` through its parent
at that stamp; the broadcast line shows the frame a TA would look at.
3 (issue 43, the TA's rules): a follower visit is a *stop* within the handout's stand-off plus
the package's move_base goal tolerance; home and time stand on their own; a marker's broadcast
is the median place of its frames broadcast while the explorer was at a target, within the
camera's reliable range (a stand-off frame earns half, the worst frame decides); a broadcast is
"on a detection" when a non-empty detection came within ``detection_recent_s`` before it (and it
is not a stored pose sent again after an empty one); a detection counts when the explorer was
at a target."""
TEMPLATE_GOAL_TOLERANCE_M = 0.05
"""The course template's move_base ``xy_goal_tolerance`` (``dwa_local_planner_params.yaml``):
a robot's goal tolerance where neither the thresholds nor the log say another."""
SCAN_TURN_RAD_S = 0.5
"""Faster than this the explorer is not scanning but turning to a goal: the course's scans
spin at 0.1-0.3 rad/s, move_base turns at up to about 2 rad/s (issue 43's packages)."""
STEADY = 0.5
"""A frame is on the marker when its median place is, and at least this share of its deciding
broadcasts are (a frame that flickers between the marker and elsewhere is not)."""
MAX_SAMPLES = 1024
"""Broadcast places kept per frame for its median (the latest; a ring, so memory stays flat)."""
MAX_VISITS = 256
MAX_FRAMES = 16
"""Broadcast frame names kept apart; past this, a new name counts as :data:`OTHER_FRAMES` (the
bound only keeps memory flat on a log that broadcasts a new name every tick)."""
OTHER_FRAMES = "(other frames)"
"""Entry times kept per disc; past this the newest replaces the last kept (the bound only keeps
memory flat on a pathological log)."""
DETECTION_MEMORY_NS = 30 * 1_000_000_000
"""How long a detection is remembered for matching broadcasts' stamps: the tf cache time
(a broadcast older than that could not be looked up in ``map`` anyway)."""


# --- observations -----------------------------------------------------------------------------


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


@dataclass(frozen=True, slots=True)
class FramePlace:
    """One frame's place as a TA judges it: the median of its deciding broadcasts."""

    frame: FrameBroadcasts
    place: tuple[float, float, float]
    error_m: float
    kind: str
    """``on`` (within the threshold of the marker), ``stand-off`` (in front of the marker's
    face, within the follower's stand-off: a goal frame, half the points) or ``off``."""
    broadcasts: int
    where: str
    """``at a target`` or ``anywhere`` (no frame of the marker was broadcast at a target)."""


@dataclass(slots=True)
class Broadcasts:
    """The broadcasts attributed to one marker: only those within one camera period after the
    detection of an image in which the course's detector saw it (a broadcast without one is no
    evidence of a detection; :func:`only_on_detection` judges it), by child frame name."""

    frames: dict[str, FrameBroadcasts] = field(default_factory=dict)

    @property
    def count(self) -> int:
        return sum(f.count for f in self.frames.values())


class Grader:
    """Observes a log's messages in log order; :meth:`report` gives the rubric."""

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
            return TEMPLATE_GOAL_TOLERANCE_M if value is None else value

        self.explorer_tolerance = tolerance(th.explorer_goal_tolerance_m)
        self.follower_tolerance = tolerance(th.follower_goal_tolerance_m)
        own = self.explorer_tolerance + th.goal_slack_m
        self.target_radius = own if own > th.target_reached_m + 1e-9 else th.target_reached_m
        """How near a target the explorer must come: v2's 0.15 m, or the package's own goal
        tolerance plus the controller's overshoot where that is more."""
        self.visit_radius = (
            math.sqrt(2.0) * th.follower_visit_m + self.follower_tolerance + th.goal_slack_m
        )
        """How near a marker the follower must stop: the handout's 0.4 m stand-off in x and
        in y, the package's goal tolerance, the overshoot (0.72 m with the template's)."""
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
        self._frame_marker: dict[str, int] = {}
        """The marker each frame name was last broadcast as (a detection's)."""
        """Per frame, the detections (image stamp, ID) it was broadcast as, the recent ones."""
        self.fiducial_messages = 0
        """Messages on ``/fiducial_transforms``, empty ones included (0: no detector ran)."""
        self.period_ns = math.ceil(1e9 / scenario.camera.rate_hz)
        """One camera period (the reports say the camera's rate)."""
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
            self._on_broadcast(tf, stamp, t_ns, times, where)

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
    ) -> None:
        """``times`` identical broadcasts of ``tf``, stamped ``stamp`` (its own, or the log time
        for a zero stamp); ``where`` is its child frame's position in ``map`` through its
        parent at that stamp (None: the parent could not be looked up)."""
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
        if not window or (self.last_fiducials_empty and (copied is None or again)):
            self.without_detection += times
            if self.without_detection_ns is None:
                self.without_detection_ns, self.without_detection_what = t_ns, what
            self.bad_broadcasts += times
        elif not on_camera:
            self.bad_broadcasts += times
        if not window or (self.last_fiducials_empty and (copied is None or again)):
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
        (identical, else nearest in the camera frame); elsewhere, the detected marker nearest
        to where it puts its frame in ``map``."""
        if on_camera:
            exact = next(((s, f) for s, f in window if f.transform == tf.transform), None)
            return exact or min(window, key=lambda sf: _apart_m(tf.transform, sf[1].transform))
        if where is None:
            return window[0]
        known = [(s, f) for s, f in window if f.fiducial_id in self.markers]
        if not known:
            return window[0]
        return min(known, key=lambda sf: math.dist(where, self.markers[sf[1].fiducial_id]))

    def found_markers(self) -> tuple[FoundMarker, ...]:
        """The markers broadcast, as :func:`marker_broadcast` judges them, with the error of
        the frame the line shows."""
        out = []
        for mid in self.broadcasts:
            places = frame_places(self, mid)
            if not places:
                continue
            shown = _shown_place(places)
            worst = shown.error_m if math.isfinite(shown.error_m) else None
            out.append(FoundMarker(mid, _place_text(places, shown), worst))
        return tuple(out)

    def resolved_thresholds(self) -> Thresholds:
        """The thresholds judged by, with the scenario's time limit filled in."""
        if self.th.time_limit_s is not None:
            return self.th
        return replace(self.th, time_limit_s=float(self.scenario.time_limit_s))

    def report(
        self, source: str, *, log_complete: bool = True, log_problem: str = ""
    ) -> GradeReport:
        """The rubric as judged from what was fed so far (a truncated log: as far as it goes)."""
        return GradeReport(
            source,
            judge(self),
            self.start_ns or 0,
            log_complete,
            log_problem,
            thresholds=self.resolved_thresholds(),
            scenario=self.scenario.name,
            rubric="usar",
            rubric_version=RUBRIC_VERSION,
        )


BROADCAST_MATCH_M = 0.005
"""How close a broadcast must be to a detection in its window (in the camera frame) to be
that detection's broadcast. A broadcaster copies the detected pose, so an honest one is exact;
a copy of an older frame's detection stamped "now" is off by the turn since that frame (about
1-2.5 cm at 0.1 rad/s and 10 Hz, 1-2.5 m away) and is, exactly, that older detection."""


def _near_a_detection(
    transform: msgs.Transform, detections: tuple[msgs.FiducialTransform, ...], within_m: float
) -> bool:
    """Does this broadcast put the marker within ``within_m`` of one of ``detections`` (in the
    camera frame)? Not when there are none."""
    return any(_apart_m(transform, f.transform) <= within_m for f in detections)


def _apart_m(a: msgs.Transform, b: msgs.Transform) -> float:
    """How far apart two transforms put their child frame's origin (metres)."""
    p, q = a.translation, b.translation
    return math.dist((p.x, p.y, p.z), (q.x, q.y, q.z))


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


# --- the rubric lines -------------------------------------------------------------------------


def _s(t_ns: int) -> str:
    """A sim time as the log, ``usar info`` and the ``usar view`` timeline show it."""
    return f"{t_ns / 1e9:.1f} s"


def _n(count: int, word: str) -> str:
    """``1 frame``, ``2 frames``."""
    return f"{count} {word}" + ("" if count == 1 else "s")


def _xy(p: tuple[float, float]) -> str:
    return f"({p[0]:.2f}, {p[1]:.2f})"


def in_order(discs: Sequence[Disc]) -> list[int | None]:
    """The arrival time at each disc, taken in order as a subsequence of the robot's arrivals.

    Greedy: each item's arrival is its first entry after the previous *reached* item's arrival;
    None for an item not reached in order (never, or only before). The one place order is
    judged, for the explorer's targets and the follower's markers alike.
    """
    out: list[int | None] = []
    prev = -1
    for d in discs:
        t = d.first_after(prev)
        out.append(t)
        if t is not None:
            prev = t
    return out


def _last_reached(names: Sequence[str], arrivals: Sequence[int | None]) -> tuple[int, str]:
    """(time, name) of the last item reached in order; (-1, "") when none was."""
    last = (-1, "")
    for name, t in zip(names, arrivals, strict=True):
        if t is not None:
            last = (t, name)
    return last


def _visit_checks(
    *,
    ids: Sequence[str],
    descriptions: Sequence[str],
    names: Sequence[str],
    discs: Sequence[Disc],
    radius: float,
    points_total: float,
    verb: str,
    order: str,
) -> list[Check]:
    """The lines "robot reached item k, in order": one wording for targets and markers."""
    arrivals = in_order(discs)
    each = points_total / max(len(discs), 1)
    checks: list[Check] = []
    prev_name = ""
    for i, d in enumerate(discs):
        t = arrivals[i]
        after = f", after {prev_name}" if prev_name else ""
        value: float | None
        evidence_ns: int | None
        if t is not None:
            stay = d.stay_at(t)
            measured = f"{verb} at {_s(t)} (closest {stay:.3f} m)"
            value, evidence_ns, evidence = stay, t, verb
        else:
            where = d.closest_evidence()
            closest = f"closest {d.closest_m:.2f} m" + (
                f" at {_s(where)}" if where is not None else ", where it started"
            )
            if d.entries:
                measured = f"{verb} only before {prev_name} (out of {order}; {closest})"
            else:
                measured = f"never {verb} ({closest})"
            value = d.closest_m if math.isfinite(d.closest_m) else None
            evidence_ns, evidence = where, ("closest approach" if where is not None else "")
        checks.append(
            Check(
                id=ids[i],
                description=descriptions[i],
                passed=t is not None,
                points=each if t is not None else 0.0,
                max_points=each,
                measured=measured,
                threshold=f"<= {radius:g} m{after}",
                evidence_ns=evidence_ns,
                value=value,
                unit="m",
                limit=radius,
                op="<=",
                evidence=evidence,
            )
        )
        if t is not None:
            prev_name = names[i]
    return checks


def explorer_targets(g: Grader) -> list[Check]:
    """``explorer.target_k``: the explorer's true position reached each target, in order."""
    n = len(g.targets)
    return _visit_checks(
        ids=[f"explorer.target_{k + 1}" for k in range(n)],
        descriptions=[
            f"explorer reached target_{k + 1} {_xy(t)}" + (" in order" if k else "")
            for k, t in enumerate(g.targets)
        ],
        names=[f"target_{k + 1}" for k in range(n)],
        discs=g.target_discs,
        radius=g.target_radius,
        points_total=12.0,
        verb="reached",
        order="order",
    )


def marker_detected(g: Grader, mid: int) -> Check:
    """``marker_k.detected``: the detector reported ID k in a frame taken while the explorer
    was at a target (stopped or turning there), a detection the mission could use; a marker
    only glimpsed while driving past does not count."""
    t = g.detected_ns.get(mid)
    frames = g.detected_frames.get(mid, 0)
    glimpsed = g.glimpsed_frames.get(mid, 0)
    each = 12.0 / max(len(g.markers), 1)
    if not g.fiducial_messages:
        measured = NO_DETECTOR
    elif t is not None:
        measured = f"in {_n(frames, 'frame')} at a target, first at {_s(t)}"
    elif glimpsed:
        first = g.glimpsed_ns[mid]
        measured = f"only glimpsed away from the targets ({_n(glimpsed, 'frame')}, first at " \
            f"{_s(first)})"
    else:
        measured = "never detected"
    return Check(
        id=f"marker_{mid}.detected",
        description=f"explorer detected marker {mid} at a target",
        passed=t is not None,
        points=each if t is not None else 0.0,
        max_points=each,
        measured=measured,
        threshold=f"at least 1 frame on {contract.FIDUCIALS} within {g.target_radius:g} m of "
        "a target",
        evidence_ns=t if t is not None else g.glimpsed_ns.get(mid),
        value=float(frames),
        unit="frames",
        limit=1.0,
        op=">=",
        evidence="first detection" if t is not None else (
            "first glimpse" if mid in g.glimpsed_ns else ""
        ),
    )


def _median(points: Sequence[tuple[float, ...]]) -> tuple[float, ...]:
    """The component-wise median (a few wild broadcasts do not move it)."""
    return tuple(statistics.median(p[i] for p in points) for i in range(len(points[0])))


def frame_places(g: Grader, mid: int) -> list[FramePlace]:
    """Each frame broadcast for marker ``mid``, placed as a TA sees it in RViz: the median of
    its broadcasts while the explorer was at a target, of detections within the reliable range
    (when no frame of the marker was broadcast so, the median of all its broadcasts); a frame
    never found in ``map`` is ``off`` with an infinite error. By frame name."""
    frames = sorted(g.broadcasts[mid].frames.values(), key=lambda f: f.frame)
    at_target = any(f.at_target for f in frames)
    marker = g.markers[mid]
    out: list[FramePlace] = []
    for f in frames:
        ring = f.at_target if at_target else f.elsewhere
        n = f.at_target_count if at_target else f.elsewhere_count
        where = "at a target" if at_target else "anywhere"
        if not ring:
            if f.failed_lookups and not (at_target and f.elsewhere):
                out.append(FramePlace(f, (math.inf,) * 3, math.inf, "off", f.count, where))
            continue
        place = _median([p for p, _ in ring])
        seen_from = _median([e for _, e in ring])
        err = math.dist(place, marker)
        limit = g.th.marker_map_error_m
        on = sum(math.dist(p, marker) <= limit for p, _ in ring) >= STEADY * len(ring)
        steady = sum(math.dist(p, place) <= limit for p, _ in ring) >= STEADY * len(ring)
        if err <= limit and on:
            kind = "on"
        elif steady and _stand_off(g, mid, place, seen_from):
            kind = "stand-off"
        else:
            kind = "off"
        out.append(FramePlace(f, (place[0], place[1], place[2]), err, kind, n, where))
    return out


def _stand_off(
    g: Grader, mid: int, place: tuple[float, ...], seen_from: tuple[float, ...]
) -> bool:
    """A frame put deliberately in front of the marker: on its face's side, towards the camera,
    no farther than the follower's stand-off (0.4 m in x and in y) plus the threshold."""
    x, y, _z = g.markers[mid]
    yaw = g.marker_yaw.get(mid, 0.0)
    vx, vy = place[0] - x, place[1] - y
    ahead = vx * math.cos(yaw) + vy * math.sin(yaw)
    cx, cy = seen_from[0] - x, seen_from[1] - y
    # between the marker and the camera: within 45 degrees of the way to the camera (an
    # offset sideways, along the image's x, is a wrong frame, not a goal in front of it)
    apart = math.hypot(vx, vy)
    camera_side = cx * vx + cy * vy > math.cos(math.pi / 4) * math.hypot(cx, cy) * apart
    within = apart <= math.sqrt(2.0) * g.th.follower_visit_m + g.th.marker_map_error_m
    return ahead > 0.0 and camera_side and within


def _shown_place(places: Sequence[FramePlace]) -> FramePlace:
    """The frame the line shows: the worst ``off`` one (it decides), else the most broadcast
    ``on`` one, else the most broadcast stand-off."""
    off = [p for p in places if p.kind == "off"]
    if off:
        return max(off, key=lambda p: (p.error_m, p.frame.frame))
    rank = {"on": 0, "stand-off": 1}
    return min(places, key=lambda p: (rank[p.kind], -p.broadcasts, p.frame.frame))


def _place_text(places: Sequence[FramePlace], shown: FramePlace) -> str:
    """What a marker's broadcasts measured, in words (the line's and the record summary's)."""
    others = len(places) - 1
    also = f" (worst of {len(places)} frames)" if shown.kind == "off" and others else (
        f" (and {_n(others, 'other frame')})" if others else ""
    )
    head = f"{shown.frame.frame}: median of {_n(shown.broadcasts, 'broadcast')} {shown.where}"
    if not math.isfinite(shown.error_m):
        return f"{shown.frame.frame}: not found in {contract.MAP} or not finite{also}"
    text = f"{head}, {shown.error_m * 100:.1f} cm from the marker"
    if shown.kind == "stand-off":
        text += ": a stand-off frame in front of it (half the points)"
    return text + also


def _stamps_text(frame: str, stamps: tuple[int, int]) -> str:
    """``my_frame stamped 12.350 s, image 12.300 s``: which broadcast a line used."""
    return f"{frame} stamped {stamps[0] / 1e9:.3f} s, image {stamps[1] / 1e9:.3f} s"


def marker_broadcast(g: Grader, mid: int) -> Check:
    """``marker_k.broadcast``: the frames broadcast on ``/tf`` (any name) as detections of
    marker k, each placed as a TA sees it in RViz (:func:`frame_places`): every frame on the
    marker passes; a stand-off frame alone earns half; one frame off the marker fails the line
    (several frames for one detection are judged by the worst: a shotgun earns nothing)."""
    places = frame_places(g, mid)
    limit = g.th.marker_map_error_m
    each = 8.0 / max(len(g.markers), 1)
    recent = f"{g.th.detection_recent_s:g} s"
    if not places:
        measured = (
            "nothing broadcast on /tf"
            if g.broadcast_count == 0
            else f"no broadcast within {recent} after a detection of marker {mid}"
        )
        shown = None
        points = 0.0
    else:
        shown = _shown_place(places)
        measured = _place_text(places, shown)
        points = {"on": each, "stand-off": each / 2, "off": 0.0}[shown.kind]
    ok = shown is not None and shown.kind == "on"
    if shown is None:
        evidence_ns, evidence = None, ""
    elif shown.kind == "off":
        f = shown.frame
        evidence_ns, evidence = f.worst_ns, "worst broadcast: " + _stamps_text(
            f.frame, f.worst_stamp
        )
    else:
        f = shown.frame
        evidence_ns, evidence = f.first_ns, "first broadcast: " + _stamps_text(
            f.frame, f.first_stamp
        )
    return Check(
        id=f"marker_{mid}.broadcast",
        description=f"marker {mid} broadcast on /tf (any frame name), where it is",
        passed=ok,
        points=points,
        max_points=each,
        measured=measured,
        threshold=f"median at a target within {limit * 100:g} cm, each frame (a stand-off "
        "frame: half)",
        evidence_ns=evidence_ns,
        value=shown.error_m if shown is not None and math.isfinite(shown.error_m) else None,
        unit="m",
        limit=limit,
        op="<=",
        evidence=evidence,
    )


def only_on_detection(g: Grader) -> Check:
    """``marker_frame.only_on_detection``: no broadcast without a detection or off the camera.

    Every frame broadcast on ``/tf`` that is not the simulator's counts (whatever its name).
    One is without a detection when no non-empty detection came within ``detection_recent_s``
    before it, or when the latest ``/fiducial_transforms`` was empty (the marker out of view)
    and it is not a detection's first broadcast (a stored pose sent again). A queued detection
    drained late by a slow loop is a detection's. A line that judges
    broadcasts gives no credit when there were none: a mission that never broadcast (it
    crashed at its first target, or has no broadcaster yet) has shown nothing this line can
    judge, so it fails with "nothing broadcast" rather than passing by default."""
    bad = g.bad_broadcasts
    firsts = [
        (t, what)
        for t, what in (
            (g.without_detection_ns, g.without_detection_what),
            (g.wrong_parent_ns, g.wrong_parent_what),
        )
        if t is not None
    ]
    first_bad = min(firsts, default=None)
    ok = bad == 0 and g.broadcast_count > 0
    period = f"{g.th.detection_recent_s:g} s"
    if g.broadcast_count == 0:
        measured = "nothing broadcast on /tf"
    else:
        names = ", ".join(list(g.broadcast_frames)[:3])
        if len(g.broadcast_frames) > 3:
            names += f" and {len(g.broadcast_frames) - 3} more"
        measured = (
            f"{_n(g.broadcast_count, 'broadcast')} ({names}), {g.without_detection} without "
            f"a detection within {period}, {g.wrong_parent} with another parent"
        )
    return Check(
        id="marker_frame.only_on_detection",
        description="frames broadcast only with a detection, child of the camera",
        passed=ok,
        points=4.0 if ok else 0.0,
        max_points=4.0,
        measured=measured,
        threshold=f"0 without a detection in the {period} before; parent "
        f"{contract.OPTICAL_FRAME}",
        evidence_ns=None if first_bad is None else first_bad[0],
        value=float(bad) if g.broadcast_count else None,  # nothing broadcast: nothing measured
        unit="broadcasts",
        limit=0.0,
        op="<=",
        evidence="" if first_bad is None else f"first bad broadcast: {first_bad[1]}",
    )


def explorer_home_before_follower(g: Grader, last_target_ns: int, last_target: str) -> Check:
    """``explorer.home_before_follower``: home after its last target, before the follower moved."""
    th = g.th
    moved = g.follower_moved_ns
    home = g.explorer_home_disc.first_after(last_target_ns)
    ok = home is not None and (moved is None or moved >= home)
    follower = "the follower never moved" if moved is None else f"follower moved at {_s(moved)}"
    after = f" after {last_target}" if last_target else ""
    if home is None:
        measured = f"never home{after} (ended {g.explorer_home_disc.last_m:.2f} m away); {follower}"
    else:
        measured = f"home at {_s(home)}; {follower}"
    if ok:
        evidence_ns, evidence = home, "explorer home"
    elif moved is not None:
        evidence_ns, evidence = moved, "follower moved"
    else:
        evidence_ns, evidence = None, ""
    return Check(
        id="explorer.home_before_follower",
        description="explorer returned home before the follower moved",
        passed=ok,
        points=4.0 if ok else 0.0,
        max_points=4.0,
        measured=measured,
        threshold=f"home within {th.home_m:g} m after the last target, before the follower "
        f"moves {th.follower_moved_m:g} m",
        evidence_ns=evidence_ns,
        value=None if home is None else home / 1e9,
        unit="s",
        limit=None if moved is None else moved / 1e9,
        op="<=",
        evidence=evidence,
    )


def follower_markers(g: Grader) -> list[Check]:
    """``follower.marker_k``: the follower visited each marker, in ID order."""
    ids = list(g.marker_discs)
    return _visit_checks(
        ids=[f"follower.marker_{k}" for k in ids],
        descriptions=[f"follower stopped at marker {k} in ID order" for k in ids],
        names=[f"marker {k}" for k in ids],
        discs=list(g.marker_discs.values()),
        radius=g.visit_radius,
        points_total=12.0,
        verb="stopped",
        order="ID order",
    )


def follower_home(g: Grader) -> Check:
    """``follower.home``: the follower left home and came back, after the explorer was home
    (where the explorer never came home: after the follower moved). Judged on its own, never
    through the visits: a follower whose visits failed may still come home."""
    d = g.follower_home_disc
    explorer_home = g.explorer_home_disc.entries[0] if g.explorer_home_disc.entries else None
    after = explorer_home if explorer_home is not None else -1
    fh = d.first_after(after)
    since = "" if explorer_home is None else f" after the explorer ({_s(explorer_home)})"
    if fh is None:
        left = g.follower_moved_ns is not None
        measured = (
            f"never home{since} (ended {d.last_m:.2f} m away)" if left else "never left home"
        )
        value = d.last_m if math.isfinite(d.last_m) and left else None
    else:
        value = d.stay_at(fh)
        measured = f"home at {_s(fh)} (closest {value:.3f} m){since}"
    return Check(
        id="follower.home",
        description="follower left and returned home, after the explorer",
        passed=fh is not None,
        points=4.0 if fh is not None else 0.0,
        max_points=4.0,
        measured=measured,
        threshold=f"within {g.th.home_m:g} m of {_xy(g.follower_home)}, after leaving it",
        evidence_ns=fh,
        value=value,
        unit="m",
        limit=g.th.home_m,
        op="<=",
        evidence="" if fh is None else "follower home",
    )


def time_limit(g: Grader, follower_home_ns: int | None) -> Check:
    """``time_limit``: the mission ended (the follower home, as :func:`follower_home` judges
    it) within the limit, counted from the log start."""
    limit = g.resolved_thresholds().time_limit_s or 0.0
    t0 = g.start_ns or 0
    took = None if follower_home_ns is None else (follower_home_ns - t0) / 1e9
    ok = took is not None and took <= limit
    return Check(
        id="time_limit",
        description="whole task completed within the time limit",
        passed=ok,
        points=4.0 if ok else 0.0,
        max_points=4.0,
        measured=f"{took:.1f} s" if took is not None else "not completed (follower never home)",
        threshold=f"<= {limit:g} s",
        evidence_ns=follower_home_ns,
        value=took,
        unit="s",
        limit=limit,
        op="<=",
        evidence="" if follower_home_ns is None else "follower home",
    )


def one_cmd_vel_publisher(g: Grader, robot: str) -> Check:
    """``<robot>.cmd_vel_one_publisher``: never two different moving commands in one tick (no
    points of its own: the course's rubric loses them elsewhere on a robot that does not spin)."""
    n = g.cmd_conflicts[robot]
    first = g.cmd_conflict_ns[robot]
    return Check(
        id=f"{robot}.cmd_vel_one_publisher",
        description=f"{robot}'s cmd_vel has one publisher at a time",
        passed=n == 0,
        points=0.0,
        max_points=0.0,
        measured="no conflicting commands"
        if n == 0
        else f"{_n(n, 'tick')} with two different commands, first at {_s(first or 0)}",
        threshold="one moving command per tick",
        evidence_ns=first,
        value=float(n),
        unit="ticks",
        limit=0.0,
        op="<=",
        evidence="" if first is None else "first tick with two commands",
    )


def judge(g: Grader) -> tuple[Check, ...]:
    """Every rubric line, in rubric order, from what ``g`` observed."""
    targets = explorer_targets(g)
    last_target = _last_reached(
        [f"target_{k + 1}" for k in range(len(g.targets))], in_order(g.target_discs)
    )
    markers = follower_markers(g)
    home = follower_home(g)
    lines: list[Check] = [
        *targets,
        *(marker_detected(g, mid) for mid in g.markers),
        *(marker_broadcast(g, mid) for mid in g.markers),
        only_on_detection(g),
        explorer_home_before_follower(g, *last_target),
        *markers,
        home,
        time_limit(g, home.evidence_ns),
        *(one_cmd_vel_publisher(g, r) for r in contract.ROBOTS),
    ]
    return tuple(lines)


RUBRIC = Rubric(
    Grader,
    GRADE_TOPICS,
    REQUIRED_TOPICS,
    trusted_topics=(contract.FIDUCIALS,),
    version=RUBRIC_VERSION,
)
"""The US&R rubric, as its assignment carries it."""
