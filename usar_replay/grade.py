"""The course's live-demo rubric (60 points), checked from a log and its ground truth.

Each rubric line is a :class:`Check`: pass/fail, points, the measured value, the threshold, and
the sim time of its evidence, so a TA can jump there in the viewer. The grader is a streaming
consumer (:meth:`Grader.feed` one message at a time) so it works the same on a recorded log
(``usar grade``) and on the outputs a replay recomputes (``usar replay --grade``).

Robots are judged by the simulator's ground truth (``/ground_truth/<robot>/pose``), never by what
the mission believes; markers by ``/fiducial_transforms`` and the ``marker_frame`` broadcasts on
``/tf``, looked up in ``map`` with the same tf2 rules the mission uses.

Points (scaled per item when a scenario has more or fewer targets/markers than four):

===================================  ======  ===================================================
line (``Check.id``)                  points  passes when
===================================  ======  ===================================================
``explorer.target_k``                12      the explorer's true position came within
                                             ``target_reached_m`` of target_k *after* it reached
                                             the earlier targets it did reach (order 1..N)
``marker_k.detected``                12      ``/fiducial_transforms`` holds ID k at least once
``marker_k.broadcast``               8       ``marker_frame`` was broadcast for marker k and
                                             every such broadcast, looked up in ``map``, lies
                                             within ``marker_map_error_m`` of the true marker
``marker_frame.only_on_detection``   4       every ``marker_frame`` is a child of
                                             ``explorer_tf/camera_rgb_optical_frame`` stamped
                                             with a frame that has a detection (no broadcast at
                                             all is the ``marker_k.broadcast`` lines' failure)
``explorer.home_before_follower``    4       after its last target, the explorer came within
                                             ``home_m`` of its start before the follower moved
                                             (``follower_moved_m``)
``follower.marker_k``                12      the follower came within ``follower_visit_m`` of
                                             marker k after visiting the lower IDs it did visit
``follower.home``                    4       after its last in-order marker, the follower came
                                             within ``home_m`` of its start
``time_limit``                       4       the follower was home within the time limit
===================================  ======  ===================================================

Order is judged as a *subsequence*: target k passes when it was reached at some time after the
in-order arrival at the previous reached target, so an explorer that skips target_2 fails only
``explorer.target_2``, and one that merely drives past target_3 on its way to target_1 is not
punished (one that visits 2, 1, 3, 4 fails ``explorer.target_2``: the earliest in-order arrival
is taken, greedily). The same holds for the follower's markers in ID order. "Home" counts only
after the robot has left it, and only after its last in-order target/marker, so passing through
home mid-mission is not returning home. To judge that from a stream, the grader keeps the entry
times into each disc (a few per target; jitter on the edge does not count twice, thanks to
``reentry_m``).

Memory does not grow with the log: per target/marker/home a bounded list of entry times
(:data:`MAX_VISITS`), detections only for the last :data:`DETECTION_MEMORY_NS` of sim time, the
tf buffer's own 30 s cache, and counters.

The thresholds live in :class:`Thresholds` (one place, documented); a TA can override them with a
TOML file's ``[thresholds]`` table, same names (:func:`load_thresholds`).
"""

from __future__ import annotations

import bisect
import importlib
import math
import sys
import tomllib
from collections.abc import Iterable
from dataclasses import asdict, dataclass, field, fields, replace
from pathlib import Path
from types import ModuleType

from usar_replay import bag, msgs
from usar_replay.errors import (
    IncompleteLog,
    InvalidScenario,
    LogError,
    MissingTopic,
    UsageError,
)
from usar_replay.info import SCENARIO_ATTACHMENT
from usar_replay.scenario import Scenario, from_toml
from usar_replay.tf_tree import Buffer, TransformException, TransformListener

__all__ = [
    "GRADE_TOPICS",
    "Check",
    "GradeReport",
    "Grader",
    "Thresholds",
    "grade_file",
    "load_scenario",
    "load_thresholds",
    "rubric_for",
]

MARKER_FRAME = "marker_frame"
OPTICAL_FRAME = "explorer_tf/camera_rgb_optical_frame"
EXPLORER_TRUTH = "/ground_truth/explorer/pose"
FOLLOWER_TRUTH = "/ground_truth/follower/pose"
FIDUCIALS = "/fiducial_transforms"
GRADE_TOPICS = ("/tf_static", "/tf", FIDUCIALS, EXPLORER_TRUTH, FOLLOWER_TRUTH)
"""The topics the grader reads; everything else in a log is skipped without decoding."""
REQUIRED_TOPICS = (EXPLORER_TRUTH, FOLLOWER_TRUTH, "/tf", FIDUCIALS)
"""Without these a log cannot be graded at all (``/tf_static`` may be absent: a log of a world
whose chain is all dynamic is still gradable)."""
MAX_VISITS = 256
"""Entry times kept per disc; past this the newest replaces the last kept (a robot does not
re-enter a target hundreds of times; the bound only keeps memory flat on a pathological log)."""
DETECTION_MEMORY_NS = 30 * 1_000_000_000
"""How long a detection is remembered for matching ``marker_frame`` stamps: the tf cache time
(a broadcast older than that could not be looked up in ``map`` anyway)."""


@dataclass(frozen=True, slots=True, kw_only=True)
class Thresholds:
    """Every number the rubric is judged by. Distances in metres, times in seconds.

    Defaults follow the course: the navigation goal tolerance is 0.05 m, so 0.15 m leaves room
    for the controller's overshoot without accepting a robot that stopped short; 0.4 m is the
    assignment's suggested follower tolerance (markers are on walls).
    """

    target_reached_m: float = 0.15
    """The explorer's true base position must come this close to each lookup target."""
    marker_map_error_m: float = 0.10
    """Every ``marker_frame`` broadcast, looked up in ``map``, must be this close to the true
    marker (3-D distance between centres)."""
    home_m: float = 0.15
    """A robot is home when its true position is this close to its start."""
    follower_moved_m: float = 0.05
    """The follower has moved once its true position is this far from where it started."""
    follower_visit_m: float = 0.4
    """The follower visits a marker when its true position comes this close (course: 0.4 m)."""
    reentry_m: float = 0.05
    """A robot inside a disc must get this much farther than its radius before a later arrival
    counts as a new visit (jitter on the edge is one visit, not many)."""
    time_limit_s: float | None = None
    """None: the scenario's limit (600 s in the course)."""


def load_thresholds(path: str | Path) -> Thresholds:
    """Thresholds from a TOML file's ``[thresholds]`` table; other tables are ignored so one file
    can carry settings for several tools. Unknown names and non-positive values are errors."""
    try:
        data = tomllib.loads(Path(path).read_text(encoding="utf-8"))
    except FileNotFoundError as err:
        raise UsageError(f"{path}: no such thresholds file") from err
    except (OSError, UnicodeDecodeError) as err:
        raise UsageError(f"{path}: cannot read the thresholds file: {err}") from err
    except tomllib.TOMLDecodeError as err:
        raise UsageError(f"{path}: invalid TOML: {err}") from err
    table = data.get("thresholds")
    if not isinstance(table, dict):
        raise UsageError(f"{path}: expected a [thresholds] table, e.g. [thresholds] home_m = 0.2")
    names = [f.name for f in fields(Thresholds)]
    values: dict[str, float] = {}
    for key, value in table.items():
        if key not in names:
            raise UsageError(
                f"{path}: thresholds.{key}: unknown threshold (known: {', '.join(names)})"
            )
        if (
            not isinstance(value, (int, float))
            or isinstance(value, bool)
            or not math.isfinite(value)
            or value <= 0
        ):
            raise UsageError(f"{path}: thresholds.{key}: must be a positive number, got {value!r}")
        values[key] = float(value)
    return replace(Thresholds(), **values)


@dataclass(frozen=True, slots=True)
class Check:
    """One rubric line's verdict."""

    id: str
    description: str
    passed: bool
    points: float
    max_points: float
    measured: str
    threshold: str
    evidence_ns: int | None
    detail: str = ""


@dataclass(frozen=True, slots=True)
class GradeReport:
    """All rubric lines of one recording, plus whether the log itself was complete."""

    source: str
    checks: tuple[Check, ...]
    start_ns: int
    log_complete: bool = True
    log_problem: str = ""

    @property
    def points(self) -> float:
        return sum(c.points for c in self.checks)

    @property
    def max_points(self) -> float:
        return sum(c.max_points for c in self.checks)

    @property
    def passed(self) -> bool:
        return all(c.passed for c in self.checks)

    def check(self, check_id: str) -> Check:
        """The line with this id (KeyError when the scenario has no such line)."""
        for c in self.checks:
            if c.id == check_id:
                return c
        raise KeyError(check_id)

    def failed_ids(self) -> list[str]:
        """Ids of the lines that failed, in rubric order."""
        return [c.id for c in self.checks if not c.passed]

    def to_dict(self) -> dict[str, object]:
        return {
            "source": self.source,
            "passed": self.passed,
            "points": round(self.points, 3),
            "max_points": round(self.max_points, 3),
            "log_complete": self.log_complete,
            "log_problem": self.log_problem,
            "checks": [
                {
                    **asdict(c),
                    "evidence_s": None if c.evidence_ns is None else round(c.evidence_ns / 1e9, 3),
                }
                for c in self.checks
            ],
        }


@dataclass(slots=True)
class _Disc:
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
    closest_m: float = math.inf
    closest_ns: int | None = None

    def update(self, xy: tuple[float, float], t_ns: int) -> None:
        d = math.dist(xy, self.centre)
        if d < self.closest_m:
            self.closest_m, self.closest_ns = d, t_ns
        if d <= self.radius:
            if self.inside is False or (self.inside is None and self.count_start):
                if len(self.entries) < MAX_VISITS:
                    self.entries.append(t_ns)
                else:
                    self.entries[-1] = t_ns
            self.inside = True
        elif self.inside is None or d > self.leave:
            self.inside = False

    def first_after(self, t_ns: int) -> int | None:
        """The first arrival strictly after ``t_ns`` (entries are in time order)."""
        i = bisect.bisect_right(self.entries, t_ns)
        return self.entries[i] if i < len(self.entries) else None


@dataclass(slots=True)
class _Broadcasts:
    """The ``marker_frame`` broadcasts attributed to one marker."""

    count: int = 0
    worst_m: float = -1.0
    worst_ns: int = 0
    first_ns: int | None = None
    failed_lookups: int = 0


@dataclass(slots=True)
class _Track:
    """When a robot first moved away from where it started (ground truth)."""

    start: tuple[float, float] | None = None
    moved_ns: int | None = None


class Grader:
    """Feeds on a log's messages in log order; :meth:`report` gives the rubric."""

    def __init__(self, scenario: Scenario, thresholds: Thresholds | None = None) -> None:
        self.scenario = scenario
        self.th = th = thresholds or Thresholds()
        self.targets = [(float(t[0]), float(t[1])) for t in scenario.targets]
        self.markers = {m.id: (m.x, m.y, m.z) for m in sorted(scenario.markers, key=lambda m: m.id)}
        self.explorer_home = (scenario.explorer.x, scenario.explorer.y)
        self.follower_home = (scenario.follower.x, scenario.follower.y)
        self.buffer = Buffer(cache_time=30.0)
        self.listener = TransformListener(self.buffer)

        def disc(c: tuple[float, float], r: float, count_start: bool) -> _Disc:
            return _Disc(c, r, r + th.reentry_m, count_start)

        self.target_discs = [disc(t, th.target_reached_m, True) for t in self.targets]
        self.explorer_home_disc = disc(self.explorer_home, th.home_m, False)
        self.marker_discs = {
            k: disc(v[:2], th.follower_visit_m, True) for k, v in self.markers.items()
        }
        self.follower_home_disc = disc(self.follower_home, th.home_m, False)
        self.follower = _Track()
        self.detected_ns: dict[int, int] = {}
        self._recent: dict[int, tuple[msgs.FiducialTransform, ...]] = {}
        """Detections by image stamp, the last :data:`DETECTION_MEMORY_NS` only."""
        self.broadcasts: dict[int, _Broadcasts] = {k: _Broadcasts() for k in self.markers}
        self.broadcast_count = 0
        self.without_detection = 0
        self.without_detection_ns: int | None = None
        self.wrong_parent = 0
        self.wrong_parent_ns: int | None = None
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
        if topic == "/tf" and isinstance(msg, msgs.TFMessage):
            self.listener.on_tf(msg)
            for tf in msg.transforms:
                if tf.child_frame_id == MARKER_FRAME:
                    self._on_marker_frame(tf, t_ns)
        elif topic == EXPLORER_TRUTH and isinstance(msg, msgs.PoseStamped):
            xy = (msg.pose.position.x, msg.pose.position.y)
            for d in self.target_discs:
                d.update(xy, t_ns)
            self.explorer_home_disc.update(xy, t_ns)
        elif topic == FOLLOWER_TRUTH and isinstance(msg, msgs.PoseStamped):
            self._on_follower((msg.pose.position.x, msg.pose.position.y), t_ns)
        elif topic == FIDUCIALS and isinstance(msg, msgs.FiducialTransformArray):
            self._on_fiducials(msg, t_ns)
        elif topic == "/tf_static" and isinstance(msg, msgs.TFMessage):
            self.listener.on_tf_static(msg)

    def feed_all(self, items: Iterable[tuple[str, msgs.Message | None, int]]) -> None:
        for topic, msg, t in items:
            self.feed(topic, msg, t)

    def _on_fiducials(self, msg: msgs.FiducialTransformArray, t_ns: int) -> None:
        for f in msg.transforms:
            self.detected_ns.setdefault(f.fiducial_id, t_ns)
        if msg.transforms:
            stamp = msg.header.stamp.ns
            self._recent[stamp] = self._recent.get(stamp, ()) + msg.transforms
        # forget detections older than the tf cache (dicts keep insertion order: oldest first)
        horizon = t_ns - DETECTION_MEMORY_NS
        while self._recent:
            oldest = next(iter(self._recent))
            if oldest >= horizon:
                break
            del self._recent[oldest]

    def _on_follower(self, xy: tuple[float, float], t_ns: int) -> None:
        tr = self.follower
        if tr.start is None:
            tr.start = xy
        if tr.moved_ns is None and math.dist(xy, tr.start) > self.th.follower_moved_m:
            tr.moved_ns = t_ns
        for d in self.marker_discs.values():
            d.update(xy, t_ns)
        self.follower_home_disc.update(xy, t_ns)

    def _on_marker_frame(self, tf: msgs.TransformStamped, t_ns: int) -> None:
        self.broadcast_count += 1
        if tf.header.frame_id != OPTICAL_FRAME:
            self.wrong_parent += 1
            if self.wrong_parent_ns is None:
                self.wrong_parent_ns = t_ns
        detections = self._recent.get(tf.header.stamp.ns, ())
        if not detections:
            self.without_detection += 1
            if self.without_detection_ns is None:
                self.without_detection_ns = t_ns
        try:
            in_map = self.buffer.lookup_transform("map", MARKER_FRAME, tf.header.stamp)
        except TransformException:
            in_map = None
        mid = _detected_id(tf.transform, detections)
        if mid not in self.markers:
            if in_map is None or not self.markers:
                return  # neither an ID nor a place: only the only_on_detection line can tell
            p = in_map.transform.translation
            mid = min(self.markers, key=lambda k: math.dist((p.x, p.y, p.z), self.markers[k]))
        b = self.broadcasts[mid]
        b.count += 1
        if b.first_ns is None:
            b.first_ns = t_ns
        if in_map is None:
            b.failed_lookups += 1
            err = math.inf
        else:
            p = in_map.transform.translation
            err = math.dist((p.x, p.y, p.z), self.markers[mid])
        if err > b.worst_m:
            b.worst_m, b.worst_ns = err, t_ns

    # -- verdict ------------------------------------------------------------------------------

    def report(
        self, source: str, *, log_complete: bool = True, log_problem: str = ""
    ) -> GradeReport:
        """The rubric as judged from what was fed so far (a truncated log: as far as it goes)."""
        th = self.th
        t0 = self.start_ns or 0
        checks: list[Check] = []

        def rel(t: int | None) -> str:
            # sim time, as the log, `usar info` and the `usar view` timeline show it
            return "never" if t is None else f"sim time {t / 1e9:.1f} s"

        # explorer: targets 1..N as a subsequence of its arrivals
        n_t = max(len(self.targets), 1)
        prev_ns, prev_name = -1, ""
        for k, (target, d) in enumerate(zip(self.targets, self.target_discs, strict=True)):
            reached = d.first_after(prev_ns)
            ok = reached is not None
            measured = f"closest {d.closest_m:.3f} m"
            if not ok and d.entries:
                measured += f", reached only before {prev_name} (out of order)"
            checks.append(
                Check(
                    id=f"explorer.target_{k + 1}",
                    description=f"explorer reached target_{k + 1} {_xy(target)}"
                    + (" in order" if k else ""),
                    passed=ok,
                    points=12 / n_t if ok else 0.0,
                    max_points=12 / n_t,
                    measured=measured,
                    threshold=f"<= {th.target_reached_m:g} m"
                    + (f", after {prev_name}" if prev_name else ""),
                    evidence_ns=reached if ok else d.closest_ns,
                )
            )
            if reached is not None:
                prev_ns, prev_name = reached, f"target_{k + 1}"
        last_target_ns = prev_ns

        n_m = max(len(self.markers), 1)
        for mid in self.markers:
            t = self.detected_ns.get(mid)
            checks.append(
                Check(
                    id=f"marker_{mid}.detected",
                    description=f"explorer detected marker {mid}",
                    passed=t is not None,
                    points=12 / n_m if t is not None else 0.0,
                    max_points=12 / n_m,
                    measured="first at " + rel(t),
                    threshold=f"at least one detection on {FIDUCIALS}",
                    evidence_ns=t,
                )
            )
        for mid in self.markers:
            b = self.broadcasts[mid]
            ok = b.count > 0 and b.worst_m <= th.marker_map_error_m
            if b.count == 0:
                measured = "no broadcast"
            elif b.failed_lookups:
                measured = f"{b.count} broadcasts, {b.failed_lookups} not found in map"
            else:
                measured = f"{b.count} broadcasts, worst error {b.worst_m * 100:.1f} cm"
            checks.append(
                Check(
                    id=f"marker_{mid}.broadcast",
                    description=f"marker {mid} broadcast as {MARKER_FRAME}, near the truth in map",
                    passed=ok,
                    points=8 / n_m if ok else 0.0,
                    max_points=8 / n_m,
                    measured=measured,
                    threshold=f"every broadcast <= {th.marker_map_error_m * 100:g} cm",
                    evidence_ns=(b.first_ns if ok else b.worst_ns) if b.count else None,
                )
            )
        bad = self.without_detection + self.wrong_parent
        first_bad = min(
            (t for t in (self.without_detection_ns, self.wrong_parent_ns) if t is not None),
            default=None,
        )
        checks.append(
            Check(
                id="marker_frame.only_on_detection",
                description=f"{MARKER_FRAME} broadcast only with a detection, child of the camera",
                passed=bad == 0,
                points=4.0 if bad == 0 else 0.0,
                max_points=4.0,
                measured=f"{self.broadcast_count} broadcasts, {self.without_detection} without a "
                f"detection, {self.wrong_parent} with another parent",
                threshold=f"0 without a detection; parent {OPTICAL_FRAME}",
                evidence_ns=first_bad,
            )
        )

        moved = self.follower.moved_ns
        home = self.explorer_home_disc.first_after(last_target_ns)
        ok_home = home is not None and (moved is None or moved >= home)
        checks.append(
            Check(
                id="explorer.home_before_follower",
                description="explorer returned home before the follower moved",
                passed=ok_home,
                points=4.0 if ok_home else 0.0,
                max_points=4.0,
                measured=f"explorer home at {rel(home)}, follower moved at {rel(moved)}",
                threshold=f"home within {th.home_m:g} m after the last target; follower still "
                f"(< {th.follower_moved_m:g} m) until then",
                evidence_ns=home if home is not None else moved,
            )
        )

        # follower: markers in ID order, as a subsequence of its visits
        prev_ns, prev_name = -1, ""
        for mid, d in self.marker_discs.items():
            t = d.first_after(prev_ns)
            ok = t is not None
            measured = f"closest {d.closest_m:.3f} m, visited at {rel(t)}"
            if not ok and d.entries:
                measured = f"closest {d.closest_m:.3f} m, visited only before {prev_name}"
                measured += " (out of ID order)"
            checks.append(
                Check(
                    id=f"follower.marker_{mid}",
                    description=f"follower visited marker {mid} in ID order",
                    passed=ok,
                    points=12 / n_m if ok else 0.0,
                    max_points=12 / n_m,
                    measured=measured,
                    threshold=f"<= {th.follower_visit_m:g} m"
                    + (f", after {prev_name}" if prev_name else ""),
                    evidence_ns=t if ok else d.closest_ns,
                )
            )
            if t is not None:
                prev_ns, prev_name = t, f"marker {mid}"
        fh = self.follower_home_disc.first_after(prev_ns) if prev_name else None
        checks.append(
            Check(
                id="follower.home",
                description="follower returned home after the markers",
                passed=fh is not None,
                points=4.0 if fh is not None else 0.0,
                max_points=4.0,
                measured=f"home at {rel(fh)}" if prev_name else "visited no marker",
                threshold=f"within {th.home_m:g} m of {_xy(self.follower_home)}"
                + (f", after {prev_name}" if prev_name else ""),
                evidence_ns=fh,
            )
        )
        limit = th.time_limit_s if th.time_limit_s is not None else self.scenario.time_limit_s
        took = None if fh is None else (fh - t0) / 1e9
        ok_time = took is not None and took <= limit
        checks.append(
            Check(
                id="time_limit",
                description="whole task completed within the time limit",
                passed=ok_time,
                points=4.0 if ok_time else 0.0,
                max_points=4.0,
                measured="not completed" if took is None else f"{took:.1f} s",
                threshold=f"<= {limit:g} s",
                evidence_ns=fh,
            )
        )
        return GradeReport(source, tuple(checks), t0, log_complete, log_problem)


def _detected_id(
    transform: msgs.Transform, detections: tuple[msgs.FiducialTransform, ...]
) -> int | None:
    """Which detection a broadcast is: the identical transform (the mission copies it), else
    the detection nearest in the camera frame; None without detections."""
    if not detections:
        return None
    for f in detections:
        if f.transform == transform:
            return f.fiducial_id
    p = transform.translation
    return min(
        detections,
        key=lambda f: math.dist(
            (p.x, p.y, p.z),
            (f.transform.translation.x, f.transform.translation.y, f.transform.translation.z),
        ),
    ).fiducial_id


def _xy(p: tuple[float, float]) -> str:
    return f"({p[0]:.3f}, {p[1]:.3f})"


def load_scenario(reader: bag.BagReader) -> Scenario:
    """The scenario attached to a log (a log without one cannot be replayed or graded)."""
    text = reader.attachments.get(SCENARIO_ATTACHMENT)
    if text is None:
        if reader.damage is not None:
            raise IncompleteLog(
                f"{reader.path}: {reader.damage.describe()}; its {SCENARIO_ATTACHMENT} attachment"
                " is not in the readable part, so it cannot be replayed or graded"
            )
        raise MissingTopic(
            f"{reader.path}: no {SCENARIO_ATTACHMENT} attached; record it with `usar record`"
        )
    try:
        source = text.decode("utf-8")
    except UnicodeDecodeError as err:
        raise LogError(f"{reader.path}: the attached {SCENARIO_ATTACHMENT} is not text") from err
    try:
        return from_toml(source, source=f"{reader.path}:{SCENARIO_ATTACHMENT}")
    except InvalidScenario as err:  # a bad attachment is a corrupt log (3), not a usage error
        raise LogError(str(err)) from err


def rubric_for(scenario: Scenario) -> ModuleType:
    """The module holding the rubric of the scenario's assignment: it has ``Grader(scenario,
    thresholds)`` (``feed``, ``report``), ``GRADE_TOPICS`` and ``REQUIRED_TOPICS``. US&R's is
    this module. Named by the assignment, imported here (a rubric module imports this one)."""
    from usar_replay.assignment import of

    name = of(scenario).rubric_module
    return sys.modules[__name__] if name == __name__ else importlib.import_module(name)


def grade_file(path: str | Path, thresholds: Thresholds | None = None) -> GradeReport:
    """Grade one recording as recorded (no replay). A damaged log is graded as far as it goes.

    Only :data:`GRADE_TOPICS` are read and decoded (camera frames are skipped), which is what
    makes ``usar grade`` fast. Raises :class:`MissingTopic` for a complete log that lacks a topic
    the rubric needs (a damaged one is graded anyway: the missing part may be past the damage).
    """
    reader = bag.BagReader(path)
    scenario = load_scenario(reader)
    rubric = rubric_for(scenario)
    grader = rubric.Grader(scenario, thresholds)
    grader.start_ns = reader.start_ns  # the run's clock starts with the log, whatever topic
    if reader.damage is None:
        missing = [t for t in rubric.REQUIRED_TOPICS if t not in reader.topics]
        if missing:
            raise MissingTopic(
                f"{path}: topic {missing[0]} is missing; it cannot be graded"
                + (f" (also missing: {', '.join(missing[1:])})" if missing[1:] else "")
            )
    for m in reader.messages(rubric.GRADE_TOPICS):
        grader.feed(m.topic, m.msg, m.log_time_ns)
    problem = ""
    if reader.damage is not None:
        problem = reader.damage.describe()
    elif reader.status != "complete":
        problem = f"the recording was {reader.status}"
    return grader.report(str(path), log_complete=not problem, log_problem=problem)
