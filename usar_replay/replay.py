"""`usar replay`: re-run the mission's thinking from a log and prove it reproduces the recording.

The recorded *inputs* (``/tf_static``, the simulator's ``/tf``, odometry, ``CameraInfo``, camera
frames) are fed in log order to a fresh :class:`usar_replay.mission.Mission`, the very code that
ran live (detector, broadcaster, listener, explorer, follower goal computation). Every message it
publishes is compared with the recorded one on the same topic, in order: same sim time and the
same CDR bytes. The first divergence is reported with its topic, sim time, field and both values.

Streaming: replayed and recorded outputs meet within a few messages of each other (the recorder
wrote each output right after the input that caused it), so the comparison holds only a short
queue per topic; memory does not grow with the log.

Regression mode: with changed settings (``--set detector.dictionary=DICT_5X5_50``) divergence is
expected; the report then says *what changed*: detections gained or lost per marker, stored marker
poses moved, follower goals moved.
"""

from __future__ import annotations

import dataclasses
import hashlib
import math
import tomllib
from collections import deque
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from usar_replay import bag, msgs
from usar_replay.errors import IncompleteLog, MissingTopic, UsageError
from usar_replay.info import SCENARIO_ATTACHMENT
from usar_replay.mission import INPUT_TOPICS, MARKER_FRAME, Mission, MissionSettings
from usar_replay.nav import OccupancyGrid
from usar_replay.scenario import Scenario, from_toml

__all__ = [
    "Divergence",
    "ReplayReport",
    "TopicComparison",
    "apply_overrides",
    "load_scenario",
    "replay",
]

RECORDER_LOG_NAME = "record"
"""``Log.name`` of lines the recorder itself writes to ``/rosout``."""
MISSION_OWNED_FRAMES = frozenset({MARKER_FRAME})
"""Child frames only the mission broadcasts: a ``/tf`` message of these is an output, not input."""


@dataclass(slots=True)
class TopicComparison:
    topic: str
    recorded: int = 0
    replayed: int = 0
    identical: int = 0

    @property
    def all_identical(self) -> bool:
        return self.recorded == self.replayed == self.identical


@dataclass(frozen=True, slots=True)
class Divergence:
    """The first place where replay and recording differ."""

    topic: str
    index: int
    recorded_ns: int | None
    replayed_ns: int | None
    field: str
    recorded_value: str
    replayed_value: str

    def describe(self, start_ns: int) -> str:
        t = self.recorded_ns if self.recorded_ns is not None else self.replayed_ns
        when = "?" if t is None else f"{(t - start_ns) / 1e9:.3f} s"
        return (
            f"{self.topic} message #{self.index} at sim time {when}: {self.field}: "
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

    def lines(self) -> list[str]:
        out: list[str] = []
        for mid in sorted(set(self.detections_recorded) | set(self.detections_replayed)):
            a, b = self.detections_recorded.get(mid, 0), self.detections_replayed.get(mid, 0)
            if a != b:
                out.append(f"marker {mid}: detections {a} -> {b} ({b - a:+d})")
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
    source: str
    start_ns: int
    topics: dict[str, TopicComparison]
    divergence: Divergence | None
    digest: str
    inputs: int
    changes: Changes
    regression: bool
    log_problem: str = ""

    @property
    def identical(self) -> bool:
        return self.divergence is None and all(t.all_identical for t in self.topics.values())

    def lines(self) -> list[str]:
        out = [f"Replay of {self.source}: {self.inputs} recorded inputs fed to the mission"]
        width = max((len(t) for t in self.topics), default=0)
        for name, t in sorted(self.topics.items()):
            mark = "identical" if t.all_identical else "DIFFERENT"
            out.append(
                f"  {name:<{width}}  recorded {t.recorded:>6}  replayed {t.replayed:>6}  {mark}"
            )
        if self.divergence is not None:
            out.append("First divergence: " + self.divergence.describe(self.start_ns))
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


def load_scenario(reader: bag.BagReader) -> Scenario:
    """The scenario attached to a log (a log without one cannot be replayed or graded)."""
    text = reader.attachments.get(SCENARIO_ATTACHMENT)
    if text is None:
        raise MissingTopic(
            f"{reader.path}: no {SCENARIO_ATTACHMENT} attached; record it with `usar record`"
        )
    return from_toml(text.decode(), source=f"{reader.path}:{SCENARIO_ATTACHMENT}")


def apply_overrides(settings: MissionSettings, overrides: Mapping[str, str]) -> MissionSettings:
    """``{"detector.dictionary": "DICT_5X5_50", "max_detection_range": "2.0"}`` -> new settings.

    Values are parsed with the type of the field they replace; unknown names are usage errors.
    """
    det_over: dict[str, Any] = {}
    top_over: dict[str, Any] = {}
    for key, raw in sorted(overrides.items()):
        if key.startswith("detector."):
            target, name = settings.detector, key.removeprefix("detector.")
            det_over[name] = _parse_field(target, name, raw, key)
        else:
            name = key.removeprefix("mission.")
            top_over[name] = _parse_field(settings, name, raw, key)
    detector = dataclasses.replace(settings.detector, **det_over) if det_over else settings.detector
    return dataclasses.replace(settings, detector=detector, **top_over)


def _parse_field(obj: Any, name: str, raw: str, key: str) -> Any:
    names = {f.name: f for f in dataclasses.fields(obj)}
    if name not in names:
        raise UsageError(f"--set {key}: unknown setting (known: {', '.join(sorted(names))})")
    current = getattr(obj, name)
    try:
        if isinstance(current, bool):
            return raw.lower() in ("1", "true", "yes", "on")
        if isinstance(current, int):
            return int(raw)
        if isinstance(current, float):
            return float(raw)
    except ValueError as err:
        raise UsageError(f"--set {key}: expected a {type(current).__name__}, got {raw!r}") from err
    return raw


def settings_from_toml(path: str | Path, base: MissionSettings) -> MissionSettings:
    """Settings overrides from a TOML file: ``[detector]`` and ``[mission]`` tables."""
    try:
        data = tomllib.loads(Path(path).read_text())
    except (OSError, tomllib.TOMLDecodeError) as err:
        raise UsageError(f"{path}: cannot read settings: {err}") from err
    flat: dict[str, str] = {}
    for table, values in data.items():
        if not isinstance(values, dict):
            raise UsageError(f"{path}: {table}: expected a table like [detector]")
        for k, v in values.items():
            flat[f"{table}.{k}"] = str(v).lower() if isinstance(v, bool) else str(v)
    return apply_overrides(base, flat)


def _is_mission_output(topic: str, msg: msgs.Message | None, outputs: set[str]) -> bool:
    if topic == "/rosout" and isinstance(msg, msgs.Log) and msg.name == RECORDER_LOG_NAME:
        return False  # the recorder's own notes (e.g. a hard stop) are not the mission's
    if topic == "/tf" and isinstance(msg, msgs.TFMessage):
        return bool(msg.transforms) and all(
            t.child_frame_id in MISSION_OWNED_FRAMES for t in msg.transforms
        )
    return topic in outputs


def _first_field_difference(a: Any, b: Any, path: str = "") -> tuple[str, str, str] | None:
    if isinstance(a, msgs.Message) and isinstance(b, msgs.Message):
        for f in dataclasses.fields(a):
            d = _first_field_difference(getattr(a, f.name), getattr(b, f.name), f"{path}.{f.name}")
            if d is not None:
                return d
        return None
    if isinstance(a, tuple) and isinstance(b, tuple):
        if len(a) != len(b):
            return (f"{path} (length)", str(len(a)), str(len(b)))
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            d = _first_field_difference(x, y, f"{path}[{i}]")
            if d is not None:
                return d
        return None
    if isinstance(a, bytes) and isinstance(b, bytes):
        if a == b:
            return None
        return (f"{path} (bytes)", f"{len(a)} bytes", f"{len(b)} bytes")
    if a != b or (isinstance(a, float) and math.copysign(1, a) != math.copysign(1, b)):
        return (path.lstrip("."), repr(a), repr(b))
    return None


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


def replay(
    path: str | Path,
    settings: MissionSettings | None = None,
    *,
    grade_sink: Callable[[str, msgs.Message | None, int], None] | None = None,
    regression: bool = False,
) -> ReplayReport:
    """Replay ``path``; ``grade_sink`` receives the stream a grader should see (inputs, ground
    truth and the *replayed* outputs) so ``usar replay --grade`` grades what replay computed."""
    reader = bag.BagReader(path)
    scenario = load_scenario(reader)
    for needed in ("/tf", "/explorer/odom", "/explorer/camera/rgb/image_raw/compressed"):
        if needed not in reader.topics:
            raise MissingTopic(f"{path}: topic {needed} is missing; it cannot be replayed")
    settings = settings or MissionSettings()
    mission = Mission(scenario, OccupancyGrid.from_scenario(scenario), settings)
    topics: dict[str, TopicComparison] = {}
    pending_rec: dict[str, deque[tuple[int, bytes, msgs.Message | None]]] = {}
    pending_rep: dict[str, deque[tuple[int, bytes, msgs.Message]]] = {}
    index: dict[str, int] = {}
    digest = hashlib.sha256()
    divergence: Divergence | None = None
    changes = Changes()
    inputs = 0

    def compare(topic: str) -> None:
        nonlocal divergence
        rec_q, rep_q = pending_rec.get(topic), pending_rep.get(topic)
        while rec_q and rep_q:
            rt, rdata, rmsg = rec_q.popleft()
            pt, pdata, pmsg = rep_q.popleft()
            i = index.get(topic, 0)
            index[topic] = i + 1
            same = rt == pt and rdata == pdata
            if same:
                topics[topic].identical += 1
            elif divergence is None:
                if rt != pt:
                    fld, a, b = "log time", str(rt), str(pt)
                else:
                    recorded = (
                        rmsg if rmsg is not None else bag.decode(rdata, type(pmsg).__msgtype__)
                    )
                    diff = _first_field_difference(recorded, pmsg)
                    fld, a, b = diff if diff is not None else ("(bytes)", "", "")
                divergence = Divergence(topic, i, rt, pt, fld, a, b)

    def key_for(topic: str, msg: msgs.Message | None) -> str:
        return "/tf (marker_frame)" if topic == "/tf" else topic

    for m in reader.messages():
        topic, t = m.topic, m.log_time_ns
        if _is_mission_output(topic, m.msg, set(OUTPUT_TOPICS)):
            k = key_for(topic, m.msg)
            topics.setdefault(k, TopicComparison(k)).recorded += 1
            pending_rec.setdefault(k, deque()).append((t, m.data, m.msg))
            _note_changes(changes, topic, m.msg, recorded=True)
            compare(k)
            continue
        if grade_sink is not None:
            grade_sink(topic, m.msg, t)
        if topic not in INPUT_TOPICS or m.msg is None:
            continue
        inputs += 1
        for out_topic, out_msg in mission.on_message(topic, m.msg, t):
            data = bag.encode(out_msg)
            k = key_for(out_topic, out_msg)
            digest.update(k.encode() + t.to_bytes(8, "little") + data)
            topics.setdefault(k, TopicComparison(k)).replayed += 1
            pending_rep.setdefault(k, deque()).append((t, data, out_msg))
            _note_changes(changes, out_topic, out_msg, recorded=False)
            if grade_sink is not None:
                grade_sink(out_topic, out_msg, t)
            compare(k)
    for k in sorted(set(pending_rec) | set(pending_rep)):
        rec_q, rep_q = pending_rec.get(k) or deque(), pending_rep.get(k) or deque()
        if (rec_q or rep_q) and divergence is None:
            i = index.get(k, 0)
            rec = rec_q[0] if rec_q else None
            rep = rep_q[0] if rep_q else None
            divergence = Divergence(
                k,
                i,
                rec[0] if rec else None,
                rep[0] if rep else None,
                "message count",
                "a message" if rec else "nothing",
                "a message" if rep else "nothing",
            )
    problem = reader.damage.describe() if reader.damage else ""
    report = ReplayReport(
        source=str(path),
        start_ns=reader.start_ns,
        topics=topics,
        divergence=divergence,
        digest=digest.hexdigest(),
        inputs=inputs,
        changes=changes,
        regression=regression,
        log_problem=problem,
    )
    if reader.damage is not None and grade_sink is None:
        raise IncompleteLog(f"{path}: {problem}; replayed up to there")
    return report


def _note_changes(ch: Changes, topic: str, msg: msgs.Message | None, *, recorded: bool) -> None:
    if topic == "/fiducial_transforms" and isinstance(msg, msgs.FiducialTransformArray):
        counts = ch.detections_recorded if recorded else ch.detections_replayed
        for f in msg.transforms:
            counts[f.fiducial_id] = counts.get(f.fiducial_id, 0) + 1
    elif topic == "/explorer/marker_poses" and isinstance(msg, msgs.FiducialTransformArray):
        store = ch.markers_recorded if recorded else ch.markers_replayed
        for f in msg.transforms:
            v = f.transform.translation
            store[f.fiducial_id] = (v.x, v.y, v.z)
    elif topic == "/follower/goal" and isinstance(msg, msgs.PoseStamped):
        goals = ch.goals_recorded if recorded else ch.goals_replayed
        goals.append((msg.pose.position.x, msg.pose.position.y))


def iter_log(reader: bag.BagReader) -> Iterator[tuple[str, msgs.Message | None, int]]:
    """(topic, message, log time) of a whole log, for the grader."""
    for m in reader.messages():
        yield m.topic, m.msg, m.log_time_ns
