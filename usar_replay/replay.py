"""`usar replay`: re-run the mission's thinking from a log and prove it reproduces the recording.

The recorded *inputs* (``/tf_static``, the simulator's ``/tf``, odometry, ``CameraInfo``, camera
frames) are fed in log order to a fresh :class:`usar_replay.mission.Mission`, the very code that
ran live (detector, broadcaster, listener, explorer, follower goal computation). Every message it
publishes is compared with the recorded one on the same topic at the same sim time: the same CDR
bytes. The report gives counts per topic, the first divergence (topic, sim time, field, both
values) and a sha256 digest of the replayed outputs (:func:`outputs_digest` computes the same
digest over a log's recorded outputs, so two machines can compare replays by one line).

Streaming, and why it is exact: the recorder writes each output at the sim time of the input that
caused it, right after that input. So once the log moves past sim time *t*, every output of time
*t*, recorded or replayed, has been seen; whatever is still unmatched then is a divergence (a
message one side has and the other lacks). The comparison therefore holds only the outputs of
the current sim time, the detector's look-ahead holds a fixed number of frames, and
:class:`Changes` holds per-marker counters: memory does not grow with the log. (The mission's tf
buffer keeps 30 s of sim time; the grader's state is bounded too, see :mod:`usar_replay.grade`.)

Speed, without changing a byte: only what is consumed is decoded (recorded outputs are compared
as bytes and decoded only to explain a divergence; ground truth only when grading); the pure
detector runs on upcoming frames in worker threads while the mission works (OpenCV releases the
GIL in PNG decoding and marker detection), and a frame whose bytes equal the previous frame's
(the explorer standing still) reuses that frame's detections. See :class:`_DetectAhead`.

Regression mode: with changed settings (``--set detector.dictionary=DICT_5X5_50``) divergence is
expected; the report then says *what changed*: detections gained or lost per marker, stored marker
poses moved, follower goals moved.
"""

from __future__ import annotations

import dataclasses
import hashlib
import math
import os
import tomllib
from collections import deque
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from types import TracebackType
from typing import Any

from usar_replay import bag, msgs
from usar_replay import detect as detect_mod
from usar_replay.detect import DetectError
from usar_replay.errors import LogError, MissingTopic, UsageError
from usar_replay.grade import load_scenario
from usar_replay.mission import (
    CAMERA_INFO_TOPIC,
    IMAGE_TOPIC,
    INPUT_TOPICS,
    MARKER_FRAME,
    Mission,
    MissionSettings,
)
from usar_replay.nav import OccupancyGrid

__all__ = [
    "OUTPUT_TOPICS",
    "Changes",
    "Divergence",
    "ReplayReport",
    "TopicComparison",
    "apply_overrides",
    "load_scenario",
    "outputs_digest",
    "replay",
    "settings_from_toml",
]

RECORDER_LOG_NAME = "record"
"""``Log.name`` of lines the recorder itself writes to ``/rosout``."""
MISSION_OWNED_FRAMES = frozenset({MARKER_FRAME})
"""Child frames only the mission broadcasts: a ``/tf`` message of these is an output, not input."""
MARKER_TF_KEY = "/tf (marker_frame)"
"""How the mission's own ``/tf`` messages are named in the report (the simulator's are inputs)."""

OUTPUT_TOPICS = frozenset(
    {
        "/fiducial_transforms",
        "/explorer/marker_poses",
        "/explorer/cmd_vel",
        "/follower/cmd_vel",
        "/explorer/goal",
        "/follower/goal",
        "/explorer/plan",
        "/follower/plan",
        "/explorer/goal_status",
        "/follower/goal_status",
        "/rosout",
    }
)
"""Topics the mission publishes (plus ``/tf`` messages of :data:`MISSION_OWNED_FRAMES`)."""
CHANGE_TOPICS = frozenset({"/fiducial_transforms", "/explorer/marker_poses", "/follower/goal"})
"""Recorded outputs decoded up front because :class:`Changes` reads them; the other recorded
outputs are compared as bytes and decoded only to explain a divergence."""
LOOK_AHEAD_FRAMES = 8
"""Camera frames the detector works on ahead of the mission (bounds the look-ahead buffer)."""


# --- settings -----------------------------------------------------------------------------------


_TRUE = frozenset({"1", "true", "yes", "on"})
_FALSE = frozenset({"0", "false", "no", "off"})


def apply_overrides(settings: MissionSettings, overrides: Mapping[str, str]) -> MissionSettings:
    """``{"detector.dictionary": "DICT_5X5_50", "max_detection_range": "2.0"}`` -> new settings.

    Names are ``detector.<field>`` or ``[mission.]<field>``; values are parsed with the type of
    the field they replace. Unknown names and unparsable values are usage errors (exit 2), so a
    typo never silently replays the unchanged mission.
    """
    det_over: dict[str, Any] = {}
    top_over: dict[str, Any] = {}
    for key, raw in sorted(overrides.items()):
        if key.startswith("detector."):
            det_over[key.removeprefix("detector.")] = _parse_field(
                settings.detector, key.removeprefix("detector."), raw, key
            )
        else:
            name = key.removeprefix("mission.")
            top_over[name] = _parse_field(settings, name, raw, key)
    detector = dataclasses.replace(settings.detector, **det_over) if det_over else settings.detector
    return dataclasses.replace(settings, detector=detector, **top_over)


def _parse_field(obj: Any, name: str, raw: str, key: str) -> Any:
    names = {f.name for f in dataclasses.fields(obj)}
    if name not in names:
        prefix = "detector." if isinstance(obj, detect_mod.DetectorParams) else ""
        known = ", ".join(prefix + n for n in sorted(names))
        raise UsageError(f"--set {key}: unknown setting (known: {known})")
    current = getattr(obj, name)
    text = raw.strip()
    if isinstance(current, bool):
        if text.lower() in _TRUE:
            return True
        if text.lower() in _FALSE:
            return False
        raise UsageError(f"--set {key}: expected true or false, got {raw!r}")
    if isinstance(current, (int, float)):
        kind = type(current)
        try:
            value = kind(text)
        except ValueError as err:
            raise UsageError(f"--set {key}: expected a {kind.__name__}, got {raw!r}") from err
        if not math.isfinite(value):
            raise UsageError(f"--set {key}: expected a finite number, got {raw!r}")
        return value
    if isinstance(current, str):
        return text
    raise UsageError(f"--set {key}: a group of settings; set one of its fields, e.g. {key}.NAME")


def settings_from_toml(path: str | Path, base: MissionSettings) -> MissionSettings:
    """Settings overrides from a TOML file: ``[detector]`` and ``[mission]`` tables (top-level
    keys are mission settings; a ``[thresholds]`` table is the grader's and is ignored here)."""
    try:
        data = tomllib.loads(Path(path).read_text(encoding="utf-8"))
    except FileNotFoundError as err:
        raise UsageError(f"{path}: no such settings file") from err
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as err:
        raise UsageError(f"{path}: cannot read settings: {err}") from err
    flat: dict[str, str] = {}

    def scalar(key: str, v: object) -> str:
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, (int, float, str)):
            return str(v)
        raise UsageError(f"{path}: {key}: expected a number, a string or a boolean")

    for table, values in data.items():
        if table == "thresholds":
            continue
        if table in ("detector", "mission") and isinstance(values, dict):
            for k, v in values.items():
                flat[f"{table}.{k}"] = scalar(f"{table}.{k}", v)
        elif isinstance(values, dict):
            raise UsageError(f"{path}: [{table}]: unknown table (use [detector] or [mission])")
        else:
            flat[table] = scalar(table, values)
    try:
        return apply_overrides(base, flat)
    except UsageError as err:
        raise UsageError(f"{path}: {str(err).removeprefix('--set ')}") from err


# --- the report -----------------------------------------------------------------------------------


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
        if topic == "/fiducial_transforms" and isinstance(msg, msgs.FiducialTransformArray):
            counts = self.detections_recorded if recorded else self.detections_replayed
            for f in msg.transforms:
                counts[f.fiducial_id] = counts.get(f.fiducial_id, 0) + 1
        elif topic == "/explorer/marker_poses" and isinstance(msg, msgs.FiducialTransformArray):
            store = self.markers_recorded if recorded else self.markers_replayed
            for f in msg.transforms:
                v = f.transform.translation
                store[f.fiducial_id] = (v.x, v.y, v.z)
        elif topic == "/follower/goal" and isinstance(msg, msgs.PoseStamped):
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
    """What a replay found; :meth:`lines` is what ``usar replay`` prints."""

    source: str
    start_ns: int
    topics: dict[str, TopicComparison]
    divergence: Divergence | None
    digest: str
    inputs: int
    changes: Changes
    regression: bool
    log_problem: str = ""
    uncompared: int = 0
    """Outputs of the last sim time of a cut log, which cannot be compared (the cut may fall
    between an input and its recorded outputs)."""
    frames_detected: int = 0
    frames_reused: int = 0
    """Frames whose bytes equalled the previous frame's, so its detections were reused."""
    peak_pending: int = 0
    """The most outputs the comparison held at once (bounded by one sim time's outputs)."""
    look_ahead_misses: int = 0
    """Frames the look-ahead predicted wrong (detected again in the mission's thread, or never
    asked for): 0 when the look-ahead mirrors the mission exactly."""

    @property
    def identical(self) -> bool:
        return self.divergence is None and all(t.all_identical for t in self.topics.values())

    def lines(self) -> list[str]:
        out = [f"Replay of {self.source}: {self.inputs} recorded inputs fed to the mission"]
        width = max((len(t) for t in self.topics), default=0)
        for name, t in sorted(self.topics.items()):
            mark = "identical" if t.all_identical else f"DIFFERENT ({t.identical} identical)"
            out.append(
                f"  {name:<{width}}  recorded {t.recorded:>6}  replayed {t.replayed:>6}  {mark}"
            )
        if self.divergence is not None:
            out.append("First divergence: " + self.divergence.describe(self.start_ns))
        if self.uncompared:
            out.append(
                f"{self.uncompared} outputs at the last sim time were not compared "
                "(the log ends there)"
            )
        out.append(f"Digest of replayed outputs (sha256): {self.digest}")
        if self.regression:
            changes = self.changes.lines()
            out.append("Changes with the new settings:" if changes else "No change in meaning.")
            out += [f"  {c}" for c in changes]
        out.append(
            "Replay reproduces the recording bit for bit."
            if self.identical
            else "Replay does NOT reproduce the recording."
        )
        return out


# --- comparison -----------------------------------------------------------------------------------


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


@dataclass(slots=True)
class _Pending:
    topic: str
    t: int
    data: bytes
    msgtype: str
    msg: msgs.Message | None
    index: int


class _Comparison:
    """Pairs recorded and replayed outputs per topic at each sim time (see module docstring)."""

    def __init__(self) -> None:
        self.topics: dict[str, TopicComparison] = {}
        self.rec: dict[str, deque[_Pending]] = {}
        self.rep: dict[str, deque[_Pending]] = {}
        self.open: set[str] = set()
        self.seen_rec: dict[str, int] = {}
        self.seen_rep: dict[str, int] = {}
        self.now = -1
        self.divergence: Divergence | None = None
        self.pending = 0
        self.peak_pending = 0
        """The most outputs held at once: what streaming bounds (a test checks it)."""

    def _stats(self, key: str) -> TopicComparison:
        s = self.topics.get(key)
        if s is None:
            s = self.topics[key] = TopicComparison(key)
        return s

    def advance(self, t: int) -> None:
        """The log reached sim time ``t``: what is unmatched at earlier times never will be."""
        if t <= self.now:
            return
        for key in sorted(self.open):
            self._flush(key)
        self.open.clear()
        self.now = t

    def _flush(self, key: str) -> None:
        s = self._stats(key)
        for p in self.rec.pop(key, ()):
            s.recorded += 1
            self.pending -= 1
            self._diverge(key, p.index, p.t, None, "presence", _brief(p), "nothing")
        for p in self.rep.pop(key, ()):
            s.replayed += 1
            self.pending -= 1
            self._diverge(key, p.index, None, p.t, "presence", "nothing", _brief(p))

    def add(self, key: str, p: _Pending, *, recorded: bool) -> None:
        self.advance(p.t)
        seen = self.seen_rec if recorded else self.seen_rep
        p.index = seen.get(key, 0)
        seen[key] = p.index + 1
        other = (self.rep if recorded else self.rec).get(key)
        if not other:
            (self.rec if recorded else self.rep).setdefault(key, deque()).append(p)
            self.open.add(key)
            self.pending += 1
            self.peak_pending = max(self.peak_pending, self.pending)
            return
        q = other.popleft()
        self.pending -= 1
        rec, rep = (p, q) if recorded else (q, p)
        s = self._stats(key)
        s.recorded += 1
        s.replayed += 1
        if rec.data == rep.data and rec.t == rep.t:
            s.identical += 1
            return
        if self.divergence is None:
            fld, a, b = self._explain(rec, rep)
            self._diverge(key, rec.index, rec.t, rep.t, fld, a, b)

    def _explain(self, rec: _Pending, rep: _Pending) -> tuple[str, str, str]:
        if rec.t != rep.t:
            return ("log time", str(rec.t), str(rep.t))
        try:
            a = rec.msg if rec.msg is not None else bag.decode(rec.data, rec.msgtype)
            b = rep.msg if rep.msg is not None else bag.decode(rep.data, rep.msgtype)
        except Exception:  # noqa: BLE001 - an undecodable recorded message: compare bytes only
            return ("(CDR bytes)", f"{len(rec.data)} bytes", f"{len(rep.data)} bytes")
        diff = _first_field_difference(a, b)
        if diff is None:  # equal values, different bytes (e.g. CDR padding): say so
            return ("(CDR bytes)", f"{len(rec.data)} bytes", f"{len(rep.data)} bytes")
        return diff

    def _diverge(
        self, key: str, index: int, rt: int | None, pt: int | None, fld: str, a: str, b: str
    ) -> None:
        if self.divergence is None:
            self.divergence = Divergence(key, index, rt, pt, fld, a, b)

    def finish(self, *, cut: bool) -> int:
        """End of the log; returns how many outputs were left uncompared because it was cut."""
        if not cut:
            self.advance(self.now + 1)
            return 0
        dropped = sum(len(q) for q in self.rec.values()) + sum(len(q) for q in self.rep.values())
        self.rec.clear()
        self.rep.clear()
        self.open.clear()
        self.pending = 0
        return dropped


def _brief(p: _Pending) -> str:
    """A one-glance description of a message present on one side only."""
    msg = p.msg
    if isinstance(msg, msgs.FiducialTransformArray):
        ids = [f.fiducial_id for f in msg.transforms]
        return f"a {p.msgtype.rsplit('/', 1)[-1]} with IDs {ids}"
    if isinstance(msg, msgs.Log):
        return f"a Log {msg.msg!r}"
    return f"a {p.msgtype.rsplit('/', 1)[-1]} ({len(p.data)} bytes)"


# --- reading the log ------------------------------------------------------------------------------

_OUTPUT, _INPUT, _OTHER = 0, 1, 2


@dataclass(slots=True)
class _Item:
    kind: int
    topic: str
    t: int
    data: bytes
    msgtype: str
    msg: msgs.Message | None


def _decode(m: bag.BagMessage) -> msgs.Message | None:
    try:
        return bag.decode(m.data, m.msgtype)
    except KeyError:
        return None  # a type usar-replay does not know: nobody here reads it
    except Exception as err:
        raise LogError(
            f"message on {m.topic} at {m.log_time_ns / 1e9:.3f} s cannot be decoded: {err}"
        ) from err


def _classified(reader: bag.BagReader, decode_also: frozenset[str]) -> Iterator[_Item]:
    """The log as inputs, recorded outputs and others; decodes only what someone reads."""
    inputs = frozenset(INPUT_TOPICS)
    for m in reader.messages(decode_messages=False):
        topic = m.topic
        if topic == "/tf":
            msg = _decode(m)
            own = (
                isinstance(msg, msgs.TFMessage)
                and bool(msg.transforms)
                and all(t.child_frame_id in MISSION_OWNED_FRAMES for t in msg.transforms)
            )
            kind = _OUTPUT if own else _INPUT
        elif topic == "/rosout":
            msg = _decode(m)
            recorder = isinstance(msg, msgs.Log) and msg.name == RECORDER_LOG_NAME
            kind = _OTHER if recorder else _OUTPUT
        elif topic in OUTPUT_TOPICS:
            kind, msg = _OUTPUT, (_decode(m) if topic in CHANGE_TOPICS else None)
        elif topic in inputs:
            kind, msg = _INPUT, _decode(m)
        else:
            kind, msg = _OTHER, (_decode(m) if topic in decode_also else None)
        yield _Item(kind, topic, m.log_time_ns, m.data, m.msgtype, msg)


# --- the detector, ahead of the mission -----------------------------------------------------------


@dataclass(slots=True)
class _Ahead:
    image: msgs.CompressedImage
    info: msgs.CameraInfo
    seq: int
    future: Future[msgs.FiducialTransformArray]


class _DetectAhead:
    """Runs the pure detector on upcoming frames in worker threads, ahead of the mission.

    Why this is byte-exact: :func:`usar_replay.detect.detect` is a pure function of (frame
    bytes, ``CameraInfo``, parameters, ``image_seq``), and its result's ``header`` and
    ``image_seq`` are the frame's header and the given sequence number while its detections
    depend on the pixels, the camera matrix and the parameters only. The look-ahead predicts
    exactly which (frame, info, seq) the mission will ask about (it mirrors the mission's rule:
    the latest ``CameraInfo``, a sequence number for each frame that has one), and
    :meth:`detect`, passed to the mission as its ``detector``, hands back the
    prefetched result only when the call matches the prediction in every argument; otherwise it
    simply calls the real detector. A frame whose bytes equal the previous frame's (with the same
    camera matrix and parameters) reuses that frame's detections under its own header and
    sequence number. Results are consumed in the mission's order, so scheduling never changes
    the output. Memory: at most ``window`` frames in flight.
    """

    def __init__(self, params: detect_mod.DetectorParams, workers: int, window: int) -> None:
        self.params = params
        self.workers = workers
        self.window = max(window, 1)
        self.pool = ThreadPoolExecutor(workers, "usar-detect") if workers > 0 else None
        self.ahead: dict[int, _Ahead] = {}
        self._last: tuple[bytes, msgs.CameraInfo, Future[msgs.FiducialTransformArray]] | None = None
        self.computed = 0
        self.reused = 0
        self.missed = 0
        """Calls that did not match the prediction (computed in the mission's thread)."""
        self.unused = 0
        """Frames predicted but never asked about."""
        self._real = detect_mod.detect

    def __enter__(self) -> _DetectAhead:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        for a in self.ahead.values():
            a.future.cancel()
        self.ahead.clear()
        if self.pool is not None:
            self.pool.shutdown(wait=True, cancel_futures=True)

    def _submit(self, image: msgs.CompressedImage, info: msgs.CameraInfo, seq: int) -> None:
        assert self.pool is not None
        bare_info = dataclasses.replace(info, header=msgs.Header())
        last = self._last
        if last is not None and last[0] == image.data and last[1] == bare_info:
            fut = last[2]
            self.reused += 1
        else:
            fut = self.pool.submit(self._real, image, info, self.params, seq)
            self._last = (image.data, bare_info, fut)
            self.computed += 1
        self.ahead[id(image)] = _Ahead(image, info, seq, fut)

    def look_ahead(self, items: Iterable[_Item]) -> Iterator[_Item]:
        """``items`` unchanged and in order, with frames handed to the workers ``window`` early."""
        if self.pool is None:
            yield from items
            return
        buf: deque[tuple[_Item, bool]] = deque()
        in_flight = 0
        info: msgs.CameraInfo | None = None
        seq = 0
        for it in items:
            submitted = False
            if it.kind == _INPUT:
                if it.topic == CAMERA_INFO_TOPIC and isinstance(it.msg, msgs.CameraInfo):
                    info = it.msg
                elif (
                    it.topic == IMAGE_TOPIC
                    and isinstance(it.msg, msgs.CompressedImage)
                    and info is not None
                ):
                    self._submit(it.msg, info, seq)
                    seq += 1
                    submitted = True
                    in_flight += 1
            buf.append((it, submitted))
            while in_flight > self.window:
                out, was = buf.popleft()
                in_flight -= was
                yield out
                if was:
                    self._forget(out)
        while buf:
            out, was = buf.popleft()
            yield out
            if was:
                self._forget(out)

    def _forget(self, item: _Item) -> None:
        """The consumer is done with this frame: if the mission did not ask for its detections
        (it always does today), drop them, so nothing accumulates whatever the mission does."""
        a = self.ahead.pop(id(item.msg), None)
        if a is not None:
            a.future.cancel()
            self.unused += 1

    def detect(
        self,
        image: msgs.CompressedImage,
        info: msgs.CameraInfo,
        params: detect_mod.DetectorParams,
        image_seq: int = 0,
    ) -> msgs.FiducialTransformArray:
        """Drop-in for :func:`usar_replay.detect.detect`: the same result, usually precomputed."""
        a = self.ahead.pop(id(image), None)
        if (
            a is None
            or a.image is not image
            or a.seq != image_seq
            or params != self.params
            or (a.info is not info and a.info != info)
        ):
            if a is not None:
                a.future.cancel()
            self.missed += 1
            return self._real(image, info, params, image_seq)
        result = a.future.result()
        if result.header == image.header and result.image_seq == image_seq:
            return result
        return dataclasses.replace(result, header=image.header, image_seq=image_seq)


def default_workers() -> int:
    """Detector threads: one per core, at most four. The mission's thread is mostly idle
    waiting for detections (detection is about 3/4 of a replay's CPU), and OpenCV releases the
    GIL, so on 2 cores two detector threads beat one (measured: bench/bench_replay.py)."""
    return max(1, min(4, os.cpu_count() or 1))


# --- replay -----------------------------------------------------------------------------------


def replay(
    path: str | Path,
    settings: MissionSettings | None = None,
    *,
    grade_sink: Callable[[str, msgs.Message | None, int], None] | None = None,
    grade_topics: Sequence[str] = (),
    required_topics: Sequence[str] = (),
    regression: bool = False,
    workers: int | None = None,
) -> ReplayReport:
    """Replay ``path`` with ``settings`` (default: the mission's defaults) and compare.

    ``grade_sink`` receives the stream a grader should see (inputs, ground truth and the
    *replayed* outputs, never the recorded ones) so ``usar replay --grade`` grades what replay
    computed; messages on ``grade_topics`` reach it decoded, others as None. ``required_topics``
    are topics the caller needs beyond the mission's inputs. ``workers``: detector threads
    (0: detect in the mission's thread, as live; None: :func:`default_workers`).

    A damaged or interrupted log is replayed as far as it goes; ``report.log_problem`` says so
    (the CLI exits 3). Raises :class:`MissingTopic` for a complete log without a needed topic.
    """
    reader = bag.BagReader(path)
    scenario = load_scenario(reader)
    if reader.damage is None:
        for needed in (*INPUT_TOPICS, *required_topics):
            if needed not in reader.topics:
                raise MissingTopic(f"{path}: topic {needed} is missing; it cannot be replayed")
    settings = settings or MissionSettings()
    grid = OccupancyGrid.from_scenario(scenario)
    comparison = _Comparison()
    changes = Changes()
    digest = hashlib.sha256()
    inputs = 0
    grading = frozenset(grade_topics) if grade_sink is not None else frozenset()
    n_workers = default_workers() if workers is None else max(workers, 0)
    with _DetectAhead(settings.detector, n_workers, LOOK_AHEAD_FRAMES) as ahead:
        detector = ahead.detect if n_workers > 0 else detect_mod.detect
        mission = Mission(scenario, grid, settings, detector=detector)
        for it in ahead.look_ahead(_classified(reader, grading)):
            if it.kind == _OUTPUT:
                key = MARKER_TF_KEY if it.topic == "/tf" else it.topic
                changes.note(it.topic, it.msg, recorded=True)
                comparison.add(
                    key, _Pending(it.topic, it.t, it.data, it.msgtype, it.msg, 0), recorded=True
                )
                continue
            comparison.advance(it.t)
            if grade_sink is not None:
                grade_sink(it.topic, it.msg, it.t)
            if it.kind != _INPUT or it.msg is None:
                continue
            inputs += 1
            try:
                outputs = mission.on_message(it.topic, it.msg, it.t)
            except DetectError as err:
                raise LogError(
                    f"{path}: the camera frame at sim time {it.t / 1e9:.3f} s is corrupt: {err}"
                ) from err
            for out_topic, out_msg in outputs:
                data = bag.encode(out_msg)
                digest.update(_digest_record(out_topic, it.t, data))
                changes.note(out_topic, out_msg, recorded=False)
                if grade_sink is not None:
                    grade_sink(out_topic, out_msg, it.t)
                key = MARKER_TF_KEY if out_topic == "/tf" else out_topic
                pending = _Pending(out_topic, it.t, data, out_msg.__msgtype__, out_msg, 0)
                comparison.add(key, pending, recorded=False)
        computed, reused, misses = ahead.computed, ahead.reused, ahead.missed + ahead.unused
    cut = reader.damage is not None or reader.status != "complete"
    uncompared = comparison.finish(cut=cut)
    problem = ""
    if reader.damage is not None:
        problem = reader.damage.describe()
    elif reader.status != "complete":
        problem = f"the recording was {reader.status}"
    return ReplayReport(
        source=str(path),
        start_ns=reader.start_ns,
        topics=comparison.topics,
        divergence=comparison.divergence,
        digest=digest.hexdigest(),
        inputs=inputs,
        changes=changes,
        regression=regression,
        log_problem=problem,
        uncompared=uncompared,
        frames_detected=computed,
        frames_reused=reused,
        peak_pending=comparison.peak_pending,
        look_ahead_misses=misses,
    )


def _digest_record(topic: str, t_ns: int, data: bytes) -> bytes:
    return topic.encode() + b"\0" + t_ns.to_bytes(8, "little") + data


def outputs_digest(path: str | Path) -> str:
    """sha256 of a log's *recorded* mission outputs, in the form :func:`replay` digests the
    replayed ones (topic, NUL, log time as 8 little-endian bytes, CDR bytes; in log order): a
    faithful replay has the same digest."""
    digest = hashlib.sha256()
    for it in _classified(bag.BagReader(path), frozenset()):
        if it.kind == _OUTPUT:
            digest.update(_digest_record(it.topic, it.t, it.data))
    return digest.hexdigest()
