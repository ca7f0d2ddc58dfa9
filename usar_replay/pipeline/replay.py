"""`usar replay`: re-run a mission from a log and prove it reproduces the recording.

The recorded *inputs* (everything the simulator published: ``/tf_static``, ``/map``, ``/tf``,
odometry, ``CameraInfo``, camera frames, and the course detector's ``/fiducial_transforms``, which
replay re-runs on the recorded frames, compares with the recorded ones and hands to the mission:
:mod:`usar_replay.pipeline.course_detector`) are handed, tick by tick and as the very bytes that
were logged, to a fresh mission process (:mod:`usar_replay.process.mission_process`), the same code
path as live. Every message it publishes is compared with the recorded one on the same topic at the
same sim time: the same CDR bytes. The report gives counts per topic, the first divergence (topic,
sim time, field, both values) and a sha256 digest of the replayed outputs (:func:`outputs_digest`
computes the same digest over a log's recorded outputs, so two machines can compare replays by one
line).

Which messages are inputs and which outputs is written in the log itself: each channel says who
published it (``sim``, ``mission``, ``recorder``), so a mission may broadcast any tf frame it
likes and replay still knows it as an output.

By default the replay uses the *recorded* settings and the recorded mission; ``--set`` /
``--settings`` change settings on top, ``--mission`` runs other code on the same inputs
(open loop: the robots move as recorded). Then divergence is expected, and the report says
*what changed*: detections gained or lost per marker, stored marker poses moved, follower goals
moved. With the recorded code and settings, any divergence means the mission is not
deterministic (it read a clock, an unseeded random generator or depended on thread timing), and
the report says so.

Streaming, and why it is exact: the recorder writes a tick's inputs, then its ground truth, then
the mission's outputs, all at the tick's sim time. Replay groups the log by sim time into the
same ticks, keeps a few ticks in flight in the mission process (open loop, so the inputs never
wait on outputs: the reader and the mission work at once on two cores), and compares each tick's
outputs when they come back. Memory is bounded by the window, not by the log.
"""

from __future__ import annotations

import dataclasses
import hashlib
import math
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from usar_replay.core import cdr, contract, msgs
from usar_replay.core.contract import COURSE_VIEW_TOPICS
from usar_replay.core.errors import LogError, UsageError
from usar_replay.core.safe_text import safe
from usar_replay.core.settings import RunSettings
from usar_replay.log import bag
from usar_replay.log.run import Run, open_run
from usar_replay.pipeline.course_detector import CourseDetector, mission_inputs
from usar_replay.process.mission_process import (
    MissionEnded,
    MissionLimits,
    MissionProcess,
    hide_from_mission,
)
from usar_replay.process.mission_target import MissionTarget, resolve_target
from usar_replay.sim.course_view import CourseCamera
from usar_replay.world.assignment import of as assignment_of

__all__ = [
    "MISSION_TF_KEY",
    "Changes",
    "Divergence",
    "ReplayReport",
    "TopicComparison",
    "outputs_digest",
    "replay",
]

MISSION_TF_KEY = "/tf (mission)"
"""How the mission's own ``/tf`` messages are named in the report (the simulator's are inputs)."""
CHANGE_TOPICS = frozenset({contract.FIDUCIALS, contract.MARKER_POSES, contract.goal("follower")})
"""Recorded outputs decoded up front because :class:`Changes` reads them; the other recorded
outputs are compared as bytes and decoded only to explain a divergence."""
WINDOW_TICKS = 8
"""Ticks handed to the mission process ahead of the comparison (bounds memory)."""

SIM, MISSION, RECORDER = "sim", "mission", "recorder"


def _key(topic: str) -> str:
    return MISSION_TF_KEY if topic == contract.TF else topic


@dataclass(slots=True)
class TopicComparison:
    """One output topic: how many messages each side had and how many were byte-identical."""

    topic: str
    recorded: int = 0
    replayed: int = 0
    identical: int = 0

    @property
    def all_identical(self) -> bool:
        return self.recorded == self.replayed == self.identical


@dataclass(frozen=True, slots=True)
class Divergence:
    """The first place where replay and recording differ.

    ``recorded_ns``/``replayed_ns`` are log times (= sim times, ns); None on the side that has
    no such message. ``index`` counts the messages of that topic before it (on the side that
    has it, the recording's when both do).
    """

    topic: str
    index: int
    recorded_ns: int | None
    replayed_ns: int | None
    field: str
    recorded_value: str
    replayed_value: str

    @property
    def log_time_ns(self) -> int:
        t = self.recorded_ns if self.recorded_ns is not None else self.replayed_ns
        return 0 if t is None else t

    def describe(self, start_ns: int) -> str:
        t = self.log_time_ns
        return (
            f"{self.topic} message #{self.index} at sim time {t / 1e9:.3f} s "
            f"({(t - start_ns) / 1e9:.3f} s into the log): {self.field}: "
            f"recorded {self.recorded_value}, replayed {self.replayed_value}"
        )


@dataclass(slots=True)
class Changes:
    """Regression mode: what changed between the recording and the replay, by meaning."""

    detections_recorded: dict[int, int] = field(default_factory=dict)
    detections_replayed: dict[int, int] = field(default_factory=dict)
    markers_recorded: dict[int, tuple[float, float, float]] = field(default_factory=dict)
    markers_replayed: dict[int, tuple[float, float, float]] = field(default_factory=dict)
    goals_recorded: list[tuple[float, float]] = field(default_factory=list)
    goals_replayed: list[tuple[float, float]] = field(default_factory=list)

    def note(self, topic: str, msg: msgs.Message | None, *, recorded: bool) -> None:
        """Account one output message (of either side) that carries meaning."""
        if topic == contract.FIDUCIALS and isinstance(msg, msgs.FiducialTransformArray):
            counts = self.detections_recorded if recorded else self.detections_replayed
            for f in msg.transforms:
                counts[f.fiducial_id] = counts.get(f.fiducial_id, 0) + 1
        elif topic == contract.MARKER_POSES and isinstance(msg, msgs.FiducialTransformArray):
            store = self.markers_recorded if recorded else self.markers_replayed
            for f in msg.transforms:
                v = f.transform.translation
                store[f.fiducial_id] = (v.x, v.y, v.z)
        elif topic == contract.goal("follower") and isinstance(msg, msgs.PoseStamped):
            goals = self.goals_recorded if recorded else self.goals_replayed
            goals.append((msg.pose.position.x, msg.pose.position.y))

    def lines(self) -> list[str]:
        out: list[str] = []
        for mid in sorted(set(self.detections_recorded) | set(self.detections_replayed)):
            a, b = self.detections_recorded.get(mid, 0), self.detections_replayed.get(mid, 0)
            if a != b:
                what = "gained" if b > a else "lost"
                out.append(f"marker {mid}: detections {what}: {a} -> {b} ({b - a:+d})")
        for mid in sorted(set(self.markers_recorded) | set(self.markers_replayed)):
            a3, b3 = self.markers_recorded.get(mid), self.markers_replayed.get(mid)
            if a3 is None or b3 is None:
                out.append(f"marker {mid}: stored pose {'gained' if a3 is None else 'lost'}")
            elif a3 != b3:
                out.append(f"marker {mid}: stored map pose moved {math.dist(a3, b3) * 100:.2f} cm")
        n = max(len(self.goals_recorded), len(self.goals_replayed))
        for i in range(n):
            ga = self.goals_recorded[i] if i < len(self.goals_recorded) else None
            gb = self.goals_replayed[i] if i < len(self.goals_replayed) else None
            if ga is None or gb is None:
                out.append(f"follower goal #{i}: {'gained' if ga is None else 'lost'}")
            elif ga != gb:
                out.append(f"follower goal #{i}: moved {math.dist(ga, gb) * 100:.2f} cm")
        return out


@dataclass(slots=True)
class ReplayReport:
    """What a replay found; :meth:`lines` is what ``usar replay`` prints (100 columns)."""

    source: str
    start_ns: int
    topics: dict[str, TopicComparison]
    divergence: Divergence | None
    digest: str
    inputs: int
    changes: Changes
    regression: bool
    """The code or the settings differ from the recording's: differences are changes."""
    log_problem: str = ""
    uncompared: int = 0
    """Recorded outputs of the last sim time of a cut log, which cannot be compared."""
    ticks: int = 0
    mission: str = ""
    same_code: bool = True
    settings_changed: bool = False
    mission_failure: str | None = None
    """``crashed``, ``hung``, ... when the mission process ended the replay."""
    mission_failure_detail: str = ""

    @property
    def identical(self) -> bool:
        return (
            self.mission_failure is None
            and self.divergence is None
            and all(t.all_identical for t in self.topics.values())
        )

    @property
    def nondeterministic(self) -> bool:
        """The recorded code with the recorded settings gave other outputs."""
        return not self.regression and not self.identical and self.mission_failure is None

    def lines(
        self, *, expect_changes: bool = False, before_verdict: Sequence[str] = ()
    ) -> list[str]:
        """``expect_changes``: differences were asked for (``--expect-changes``), which the
        verdict line says; ``before_verdict``: lines the caller adds above it (the rubric
        delta)."""
        out = [
            f"Replay of {self.source}",
            f"  mission {self.mission}: {self.ticks} ticks, {self.inputs} recorded inputs",
        ]
        width = max((len(t) for t in self.topics), default=0)
        for name, t in sorted(self.topics.items()):
            mark = "identical" if t.all_identical else f"DIFFERENT ({t.identical} identical)"
            out.append(
                f"  {name:<{width}}  recorded {t.recorded:>6}  replayed {t.replayed:>6}  {mark}"
            )
        if self.divergence is not None:
            out += _wrap("First divergence: " + self.divergence.describe(self.start_ns))
        if self.uncompared:
            out.append(
                f"{self.uncompared} outputs at the last sim time were not compared "
                "(the log ends there)"
            )
        out.append(f"Replayed outputs' sha256: {self.digest}")
        if self.mission_failure is not None:
            out.append(f"The mission {self.mission_failure.replace('_', ' ')} during the replay:")
            detail = safe(self.mission_failure_detail.rstrip())
            out += [f"  {line}" for line in detail.splitlines()]
        if self.regression:
            why = []
            if not self.same_code:
                why.append("other mission code")
            if self.settings_changed:
                why.append("changed settings")
            changes = self.changes.lines()
            head = f"Changes with {' and '.join(why)}:" if changes else "No change in meaning."
            out.append(head)
            out += [f"  {c}" for c in changes]
        out += before_verdict
        if self.identical:
            out.append("Replay reproduces the recording bit for bit.")
        elif self.nondeterministic:
            out.append("Replay does NOT reproduce the recording.")
            out += _wrap(
                "The code and the settings are the recorded ones, so either the mission is not "
                "deterministic (it reads a clock, an unseeded random generator, files, or "
                "depends on thread timing or the order of a set), or the log's inputs were "
                "edited after recording."
            )
        elif expect_changes:
            out.append("Replay does NOT reproduce the recording (expected: see the changes).")
        else:
            out.append("Replay does NOT reproduce the recording: see the changes above.")
        return out


def _wrap(text: str, width: int = 100) -> list[str]:
    import textwrap

    return textwrap.wrap(text, width=width, subsequent_indent="  ", break_on_hyphens=False) or [""]


@dataclass(slots=True)
class _Pending:
    topic: str
    t: int
    data: bytes
    msgtype: str
    msg: msgs.Message | None
    index: int = 0


def _first_field_difference(a: Any, b: Any, path: str = "") -> tuple[str, str, str] | None:
    """(dotted field path, recorded value, replayed value) of the first differing field."""
    if isinstance(a, msgs.Message) and isinstance(b, msgs.Message):
        if type(a) is not type(b):
            return (path.lstrip(".") or "(type)", type(a).__msgtype__, type(b).__msgtype__)
        for f in dataclasses.fields(a):
            d = _first_field_difference(getattr(a, f.name), getattr(b, f.name), f"{path}.{f.name}")
            if d is not None:
                return d
        return None
    if isinstance(a, tuple) and isinstance(b, tuple):
        if len(a) != len(b):
            return (f"{path.lstrip('.')} (length)", str(len(a)), str(len(b)))
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            d = _first_field_difference(x, y, f"{path}[{i}]")
            if d is not None:
                return d
        return None
    if isinstance(a, bytes) and isinstance(b, bytes):
        if a == b:
            return None
        n = min(len(a), len(b))
        at = next((i for i in range(n) if a[i] != b[i]), n)
        where = f"{path.lstrip('.')} (bytes, first difference at byte {at})"
        return (where, f"{len(a)} bytes", f"{len(b)} bytes")
    if isinstance(a, float) and isinstance(b, float):
        same = (a == b and math.copysign(1, a) == math.copysign(1, b)) or (
            math.isnan(a) and math.isnan(b)
        )
        return None if same else (path.lstrip("."), repr(a), repr(b))
    return None if a == b else (path.lstrip("."), repr(a), repr(b))


def _brief(p: _Pending) -> str:
    """A one-glance description of a message present on one side only."""
    msg = p.msg if p.msg is not None else _try_decode(p.data, p.msgtype)
    if isinstance(msg, msgs.FiducialTransformArray):
        ids = [f.fiducial_id for f in msg.transforms]
        return f"a {p.msgtype.rsplit('/', 1)[-1]} with IDs {ids}"
    if isinstance(msg, msgs.Log):
        return f"a Log {msg.msg!r}"
    if isinstance(msg, msgs.TFMessage):
        return f"a TFMessage of {[t.child_frame_id for t in msg.transforms]}"
    return f"a {p.msgtype.rsplit('/', 1)[-1]} ({len(p.data)} bytes)"


def _try_decode(data: bytes, msgtype: str) -> msgs.Message | None:
    try:
        return cdr.decode(data, msgtype)
    except Exception:  # noqa: BLE001 - only used to describe a message
        return None


def _explain(rec: _Pending, rep: _Pending) -> tuple[str, str, str]:
    a = rec.msg if rec.msg is not None else _try_decode(rec.data, rec.msgtype)
    b = rep.msg if rep.msg is not None else _try_decode(rep.data, rep.msgtype)
    if a is None or b is None:
        return ("(CDR bytes)", f"{len(rec.data)} bytes", f"{len(rep.data)} bytes")
    diff = _first_field_difference(a, b)
    if diff is None:  # equal values, different bytes (e.g. CDR padding): say so
        return ("(CDR bytes)", f"{len(rec.data)} bytes", f"{len(rep.data)} bytes")
    return diff


class _Comparison:
    """Compares each tick's recorded and replayed outputs, per topic, in publish order."""

    def __init__(self) -> None:
        self.topics: dict[str, TopicComparison] = {}
        self.seen_rec: dict[str, int] = {}
        self.seen_rep: dict[str, int] = {}
        self.divergence: Divergence | None = None

    def _stats(self, key: str) -> TopicComparison:
        s = self.topics.get(key)
        if s is None:
            s = self.topics[key] = TopicComparison(key)
        return s

    def tick(self, recorded: Sequence[_Pending], replayed: Sequence[_Pending]) -> None:
        rec_by: dict[str, list[_Pending]] = {}
        rep_by: dict[str, list[_Pending]] = {}
        order: list[str] = []
        for side, by, seen in (
            (recorded, rec_by, self.seen_rec),
            (replayed, rep_by, self.seen_rep),
        ):
            for p in side:
                key = _key(p.topic)
                if key not in rec_by and key not in rep_by:
                    order.append(key)
                p.index = seen.get(key, 0)
                seen[key] = p.index + 1
                by.setdefault(key, []).append(p)
        for key in order:
            a, b = rec_by.get(key, []), rep_by.get(key, [])
            s = self._stats(key)
            s.recorded += len(a)
            s.replayed += len(b)
            for x, y in zip(a, b, strict=False):
                if x.data == y.data:
                    s.identical += 1
                elif self.divergence is None:
                    fld, va, vb = _explain(x, y)
                    self.divergence = Divergence(key, x.index, x.t, y.t, fld, va, vb)
            if self.divergence is None and len(a) != len(b):
                extra = a[len(b)] if len(a) > len(b) else b[len(a)]
                recorded_side = len(a) > len(b)
                self.divergence = Divergence(
                    key,
                    extra.index,
                    extra.t if recorded_side else None,
                    None if recorded_side else extra.t,
                    "presence",
                    _brief(extra) if recorded_side else "nothing",
                    "nothing" if recorded_side else _brief(extra),
                )


@dataclass(slots=True)
class _Tick:
    t: int
    inputs: list[tuple[str, str, bytes]] = field(default_factory=list)
    recorded: list[_Pending] = field(default_factory=list)
    truth: list[bag.BagMessage] = field(default_factory=list)
    sent: bool = False
    course: list[_Pending] = field(default_factory=list)
    """The course detector's re-run on this tick's frame, compared with the recorded one."""


def _ticks(run: Run) -> Iterator[_Tick]:
    """The log grouped by sim time (one tick per time that has messages)."""
    tick: _Tick | None = None
    for m in run.messages(decode=False):
        if tick is None or m.log_time_ns != tick.t:
            if tick is not None:
                yield tick
            tick = _Tick(m.log_time_ns)
        if m.publisher == SIM:
            tick.inputs.append((m.topic, m.msgtype, m.data))
        elif m.publisher == MISSION:
            msg = _try_decode(m.data, m.msgtype) if m.topic in CHANGE_TOPICS else None
            tick.recorded.append(_Pending(m.topic, m.log_time_ns, m.data, m.msgtype, msg))
        else:
            tick.truth.append(m)
    if tick is not None:
        yield tick


GradeSink = Callable[[str, msgs.Message | None, int], None]


def replay(
    source: str | Path | Run,
    settings: RunSettings | None = None,
    *,
    mission: str | None = None,
    grade_sink: GradeSink | None = None,
    grade_topics: Sequence[str] = (),
    required_topics: Sequence[str] = (),
    limits: MissionLimits | None = None,
    window: int = WINDOW_TICKS,
    target: MissionTarget | None = None,
    process: Callable[..., MissionProcess] | None = None,
) -> ReplayReport:
    """Replay a log (a path or an opened :class:`Run`) and compare.

    ``settings``: default the recorded ones. ``mission``: default the recorded mission (the
    built-in one, or the file the log names, if it is here). ``grade_sink`` receives the stream
    a grader should see (inputs, ground truth and the *replayed* outputs, never the recorded
    ones), in time order; messages on ``grade_topics`` reach it decoded, others as None.
    ``target`` and ``process``: another mission process than a Python mission's (a ROS 1
    package: :mod:`usar_replay.ros1.replay`).

    A damaged or interrupted log is replayed as far as it goes; ``report.log_problem`` says so
    (the CLI exits 3). Raises :class:`MissingTopic` for a complete log without a needed topic.

    The phases: open and check the log, resolve the mission code (:func:`_resolve_mission`),
    feed the recorded ticks to a fresh mission process while comparing what comes back
    (:func:`_drive`, with a :class:`_Replayer` that compares, digests and feeds the grader),
    then sum up in a :class:`ReplayReport`.
    """
    run = source if isinstance(source, Run) else open_run(source)
    scenario = run.require_scenario()
    asg = assignment_of(scenario)
    run.require_topics([*asg.sim_topics, *required_topics])
    target = target or _resolve_mission(run, mission)
    use = settings or run.settings
    same_code = bool(run.mission.sha256) and target.sha256 == run.mission.sha256
    replayer = _Replayer(grade_sink, frozenset(grade_topics) if grade_sink else frozenset())
    # the course's detections are recorded inputs, re-run and compared (a log from before the
    # trusted detector has the mission's own as outputs: those replay as they ran); a
    # mission's detections on that topic are never graded
    world_detects = bool(asg.course_detections) and SIM in run.reader.publishers(
        asg.course_detections
    )
    # at the course camera's resolution, from the regions the recorder logged (a log from
    # before them reads record.course_detection as unset: its 640x480 frames, as it ran)
    course = bool(use.record.course_detection) and CourseCamera.of(scenario.camera) is not None
    redetect = (
        CourseDetector(
            use.detector,
            asg,
            scenario.camera.pixel_scale(),
            latency_ticks=use.record.detection_latency_ticks or 0,
            course=course,
        )
        if world_detects
        else None
    )
    replayer.never_graded = frozenset({asg.course_detections} - {""})
    crashed: MissionEnded | None = None
    last: _Tick | None = None
    with (process or MissionProcess)(
        target,
        asg.parameters(scenario, use),
        sim_topics=mission_inputs(asg, world_detects),
        sim_frames=asg.sim_frames,
        limits=hide_from_mission(limits, str(run.path)),  # the log holds the truth
    ) as proc:
        try:
            # other code or settings may switch the course's detector otherwise than the
            # recording did: then each tick's detections wait for the replayed switches
            # (lockstep); a faithful replay follows the recorded ones with ticks in flight
            if redetect is not None and (use != run.settings or not same_code):
                replayer.switches, window = redetect, 0
            last = _drive(run, proc, replayer, window, redetect)
        except MissionEnded as ended:
            crashed, last = ended, replayer.last
    uncompared = len(last.recorded) if (last is not None and run.problem()) else 0
    return ReplayReport(
        source=str(run.path),
        start_ns=run.start_ns,
        topics=replayer.comparison.topics,
        divergence=replayer.comparison.divergence,
        digest=replayer.digest.hexdigest(),
        inputs=replayer.inputs,
        changes=replayer.changes,
        regression=use != run.settings or not same_code,
        log_problem=run.problem(),
        uncompared=uncompared,
        ticks=replayer.ticks,
        mission=target.spec,
        same_code=same_code,
        settings_changed=use != run.settings,
        mission_failure=None if crashed is None else crashed.verdict,
        mission_failure_detail="" if crashed is None else crashed.detail,
    )


def recorded_mission(run: Run) -> str:
    """The mission the log says ran; :class:`LogError` (exit 3) when its ``mission.toml`` is
    unreadable or names none. Why not the built-in mission then: a replay must run the code
    that was recorded or the code the user names (``--mission``), never a guess (issue 33)."""
    bad = [p for p in run.problems if contract.MISSION_ATTACHMENT in p]
    if bad or not run.mission.target:
        why = bad[0] if bad else f"no {contract.MISSION_ATTACHMENT} names the mission that ran"
        raise LogError(
            f"{run.path}: {safe(why)}; it cannot be replayed as recorded: "
            "name the code with --mission FILE (or --mission builtin)"
        )
    return run.mission.target


def _resolve_mission(run: Run, mission: str | None) -> MissionTarget:
    """``--mission``, else the mission the log names (which must be here to replay)."""
    recorded_target = mission or recorded_mission(run)
    try:
        return resolve_target(recorded_target)
    except UsageError as err:
        if mission is None:
            raise UsageError(
                f"{run.path} was recorded with mission {recorded_target!r}, which is not here "
                "to replay; pass --mission FILE"
            ) from err
        raise


class _Replayer:
    """What a replay accumulates tick by tick: the comparison with the recording, the changes
    people read, the digest of the replayed outputs, and the grader's stream."""

    def __init__(self, grade_sink: GradeSink | None, decode_for_grade: frozenset[str]) -> None:
        self.grade_sink = grade_sink
        self.decode_for_grade = decode_for_grade
        self.comparison = _Comparison()
        self.changes = Changes()
        self.digest = hashlib.sha256()
        self.inputs = 0
        self.ticks = 0
        self.last: _Tick | None = None
        self.never_graded: frozenset[str] = frozenset()
        """Output topics the grader never sees from a mission (the course's detections)."""
        self.switches: CourseDetector | None = None
        """The course's detector that follows the *replayed* mission's on/off switches."""

    def feed(
        self, topic: str, msgtype: str, data: bytes, value: msgs.Message | None, t: int
    ) -> None:
        """One message to the grader (decoded only when the grader reads its topic)."""
        if self.grade_sink is None:
            return
        if value is None and topic in self.decode_for_grade:
            value = _try_decode(data, msgtype)
        self.grade_sink(topic, value, t)

    def _feed_recorded(self, tick: _Tick) -> None:
        for topic, msgtype, data in tick.inputs:
            self.feed(topic, msgtype, data, None, tick.t)
        for m in tick.truth:
            self.feed(m.topic, m.msgtype, m.data, None, tick.t)

    def skip(self, tick: _Tick) -> None:
        """A tick with nothing for the mission (or after it said it is done): the recording's
        outputs here have no replayed counterpart."""
        self._feed_recorded(tick)
        for p in tick.recorded:
            self.changes.note(p.topic, p.msg, recorded=True)
        for p in tick.course:
            self.changes.note(p.topic, p.msg, recorded=False)
        self.comparison.tick(tick.recorded, tick.course)

    def finish(self, tick: _Tick, proc: MissionProcess) -> None:
        """The mission's outputs for a sent tick: digested, compared with the recorded ones,
        and fed to the grader after the tick's inputs and truth."""
        outputs = proc.receive()
        if self.switches is not None:
            self.switches.note_outputs((topic, value) for topic, _, _, value in outputs)
        self.ticks += 1
        self.inputs += len(tick.inputs)
        replayed = list(tick.course)
        for p in tick.course:
            self.changes.note(p.topic, p.msg, recorded=False)
        for topic, msgtype, data, value in outputs:
            self.digest.update(_digest_record(topic, tick.t, data))
            self.changes.note(topic, value, recorded=False)
            replayed.append(_Pending(topic, tick.t, data, msgtype, value))
        for p in tick.recorded:
            self.changes.note(p.topic, p.msg, recorded=True)
        self.comparison.tick(tick.recorded, replayed)
        self._feed_recorded(tick)
        for topic, msgtype, data, value in outputs:
            if topic not in self.never_graded:
                self.feed(topic, msgtype, data, value, tick.t)


def _drive(
    run: Run,
    proc: MissionProcess,
    replayer: _Replayer,
    window: int,
    redetect: CourseDetector | None = None,
) -> _Tick | None:
    """Send every recorded tick to the mission process, keeping up to ``window`` ticks in
    flight (the mission thinks while the log is read), and finish each in order. Returns the
    log's last tick."""
    in_flight: deque[_Tick] = deque()
    for tick in _ticks(run):
        replayer.last = tick
        if redetect is not None:
            _redetect(redetect, tick, recorded_switches=replayer.switches is None)
        if not tick.inputs or proc.shutdown_requested:
            # ticks still in flight are finished first: the grade sink must see sim time in
            # order (a grader's tf buffer drops what arrives after newer data, TF_OLD_DATA)
            while in_flight:
                replayer.finish(in_flight.popleft(), proc)
            replayer.skip(tick)
            continue
        proc.send(tick.t, tick.inputs)
        tick.sent = True
        in_flight.append(tick)
        while len(in_flight) > max(window, 0 if replayer.switches else 1):
            replayer.finish(in_flight.popleft(), proc)
    cut = run.reader.damage is not None or run.file_state != "complete"
    while in_flight:
        tick = in_flight.popleft()
        if cut and tick is replayer.last:
            proc.receive()  # the log ends inside this tick: nothing to compare with
            break
        replayer.finish(tick, proc)
    return replayer.last


def _redetect(detector: CourseDetector, tick: _Tick, *, recorded_switches: bool) -> None:
    """Re-run the course's detector on the tick's recorded frame: the mission receives the
    re-run's detections (with the recorded settings, the recorded bytes; with ``--set
    detector.*``, the changed detector's), and the recorded ones are compared with them. The
    detector is switched by the tick's recorded outputs (``recorded_switches``), else by the
    replayed ones as they come back (:attr:`_Replayer.switches`). At the course camera's
    resolution it searches the course camera's regions the recorder logged with the frame
    (the ``recorder``'s :data:`~usar_replay.core.contract.COURSE_VIEW_TOPICS`, which the
    mission is never sent), so replay renders nothing and still re-detects from the log
    alone."""
    recorded_outputs = [(p.topic, p.msgtype, p.data) for p in tick.recorded]
    view = [(m.topic, m.msgtype, m.data) for m in tick.truth if m.topic in COURSE_VIEW_TOPICS]
    tick.inputs, recorded, redone = detector.replay_tick(
        tick.inputs, recorded_outputs if recorded_switches else [], view
    )

    def pending(items: list[tuple[str, str, bytes]]) -> list[_Pending]:
        return [_Pending(tp, tick.t, data, mt, _try_decode(data, mt)) for tp, mt, data in items]

    # first in the tick, as they were delivered: a changed frame diverges here first
    tick.recorded[:0] = pending(recorded)
    tick.course = pending(redone)


def _digest_record(topic: str, t_ns: int, data: bytes) -> bytes:
    return topic.encode() + b"\0" + t_ns.to_bytes(8, "little") + data


def outputs_digest(path: str | Path) -> str:
    """sha256 of a log's *recorded* mission outputs, in the form :func:`replay` digests the
    replayed ones (topic, NUL, log time as 8 little-endian bytes, CDR bytes; in log order): a
    faithful replay has the same digest."""
    digest = hashlib.sha256()
    for m in open_run(path).messages(decode=False):
        if m.publisher == MISSION:
            digest.update(_digest_record(m.topic, m.log_time_ns, m.data))
    return digest.hexdigest()


def check_not_damaged(report: ReplayReport) -> None:
    """Raise :class:`LogError` when the replay stopped on a corrupt frame (exit 3)."""
    if report.mission_failure and "DetectError" in report.mission_failure_detail:
        raise LogError(
            f"{report.source}: a camera frame is corrupt: {report.mission_failure_detail}"
        )
