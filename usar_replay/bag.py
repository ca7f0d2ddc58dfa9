"""The log: ROS 2 messages to and from MCAP. The only module that imports ``mcap``.

Why this shape:

* **Writing** goes through ``mcap.writer.Writer`` with rosbags' typestore doing the CDR (measured
  about 2x faster than ``mcap_ros2.Writer``, the same bytes, and it lets us write the
  ``offered_qos_profiles`` channel metadata the MCAP ``ros2`` profile requires, so ``/tf_static``
  keeps its transient-local durability in rosbag2 and Foxglove). Schemas are named
  ``pkg/msg/Type`` and their text is the ROS 2 form (``builtin_interfaces/Time stamp``), which
  rosbags, rosbag2, Foxglove and rerun all resolve.
* The file is written to ``<name>.part`` and renamed on :meth:`BagWriter.close`, so a half-written
  log never carries the final name. A run that is interrupted (Ctrl-C) still closes the file
  properly (summary, indexes) and marks it ``interrupted`` in the ``usar.status`` metadata record.
* **Reading** streams: a complete file is read through its chunk indexes one chunk at a time; a
  file without a summary (truncated: a killed process, a partial copy) is read record by record up
  to the last intact chunk, and :attr:`BagReader.damage` says how far it got. Nothing raises a
  traceback for a damaged file.
* Log time = publish time = sim time in nanoseconds. Log times never go backwards in a usar log
  (the writer refuses), so file order is time order even when the summary is lost.
"""

from __future__ import annotations

import io
import os
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

from mcap.reader import SeekingReader
from mcap.records import Attachment, Channel, Chunk, Metadata, Schema
from mcap.records import Message as McapMessage
from mcap.stream_reader import StreamReader, breakup_chunk
from mcap.writer import CompressionType, Writer

from usar_replay import __version__, contract, msgs
from usar_replay.cdr import decode, encode, schema_text, typestore
from usar_replay.errors import LogError, NotAnMcapFile

__all__ = [
    "PROFILE",
    "STATUS_METADATA",
    "RUN_METADATA",
    "BagMessage",
    "BagReader",
    "BagWriter",
    "Damage",
    "TopicInfo",
    "decode",
    "encode",
    "schema_text",
    "typestore",
]

PROFILE = "ros2"
SCHEMA_ENCODING = "ros2msg"
MESSAGE_ENCODING = "cdr"
STATUS_METADATA = contract.STATUS_METADATA
"""Metadata record written on close: ``status`` is ``complete`` or ``interrupted``."""
RUN_METADATA = contract.RUN_METADATA
"""Metadata record with the run's settings and software version (written by the recorder)."""
MCAP_MAGIC = b"\x89MCAP0\r\n"
PUBLISHER_KEY = "usar.publisher"
"""Channel metadata key: who published the channel's messages (sim, mission, recorder)."""

# rosbag2's QoS profile, in the integer form rosbag2 expects when the file has no rosbag2
# metadata record (enum values: history 1 keep_last / 3 unknown, reliability 1 reliable,
# durability 1 transient_local / 2 volatile, liveliness 1 automatic).
_INFINITE = "    sec: 2147483647\n    nsec: 4294967295\n"


def _qos_yaml(*, transient_local: bool) -> str:
    durability = 1 if transient_local else 2
    history, depth = (1, 1) if transient_local else (3, 0)
    return (
        f"- history: {history}\n  depth: {depth}\n  reliability: 1\n  durability: {durability}\n"
        f"  deadline:\n{_INFINITE}  lifespan:\n{_INFINITE}  liveliness: 1\n"
        f"  liveliness_lease_duration:\n{_INFINITE}  avoid_ros_namespace_conventions: false\n"
    )


LATCHED_TOPICS = frozenset({contract.TF_STATIC, contract.MAP_TOPIC})
"""Topics written with transient-local QoS, as a latched ROS 2 publisher offers them."""


# --- CDR lives in usar_replay.cdr (re-exported here for older callers) ------------------------


# --- writing ------------------------------------------------------------------------------------


class BagWriter:
    """Writes a usar log: one MCAP file, ``ros2`` profile, zstd chunks, indexes and summary.

    Use as a context manager. Leaving the block normally closes the file as ``complete``; leaving
    it by ``KeyboardInterrupt`` closes it as ``interrupted`` (still indexed and readable) and lets
    the interrupt go on; any other exception also closes the file, marked ``interrupted`` with the
    error's text, so a crash loses nothing that was already written.
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        *,
        chunk_size: int = 1 << 20,
        compression: str = "zstd",
    ) -> None:
        self.path = Path(path)
        self.part_path = self.path.with_name(self.path.name + ".part")
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._file: IO[bytes] = open(self.part_path, "wb")  # noqa: SIM115 - closed in close()
        comp = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4}.get(compression)
        if comp is None:
            comp = CompressionType.NONE
        self._writer = Writer(self._file, chunk_size=chunk_size, compression=comp)
        self._writer.start(profile=PROFILE, library=f"usar-replay/{__version__}")
        self._schemas: dict[str, int] = {}
        self._channels: dict[tuple[str, str], tuple[int, str]] = {}
        self._sequence: dict[tuple[str, str], int] = {}
        self._last_time = 0
        self.message_count = 0
        self.closed = False
        self.outcome = ""
        """How the run ended, written into the status record on close (see :meth:`close`)."""
        self.outcome_reason = ""

    def __enter__(self) -> BagWriter:
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: Any
    ) -> None:
        if self.closed:
            return
        if exc_type is None:
            self.close("complete", outcome=self.outcome, outcome_reason=self.outcome_reason)
        elif issubclass(exc_type, KeyboardInterrupt):
            reason = "interrupted by the user (Ctrl-C)"
            self.close("interrupted", reason=reason, outcome="interrupted", outcome_reason=reason)
        else:
            reason = f"{exc_type.__name__}: {exc}"
            self.close("interrupted", reason=reason, outcome="interrupted", outcome_reason=reason)

    def _channel(self, topic: str, msgtype: str, publisher: str) -> int:
        known = self._channels.get((topic, publisher))
        if known is not None:
            if known[1] != msgtype:
                raise ValueError(f"topic {topic} has type {known[1]}, cannot write {msgtype}")
            return known[0]
        schema_id = self._schemas.get(msgtype)
        if schema_id is None:
            schema_id = self._writer.register_schema(
                name=msgtype, encoding=SCHEMA_ENCODING, data=schema_text(msgtype).encode()
            )
            self._schemas[msgtype] = schema_id
        qos = _qos_yaml(transient_local=topic in LATCHED_TOPICS)
        channel_id = self._writer.register_channel(
            topic=topic,
            message_encoding=MESSAGE_ENCODING,
            schema_id=schema_id,
            metadata={"offered_qos_profiles": qos, PUBLISHER_KEY: publisher},
        )
        self._channels[(topic, publisher)] = (channel_id, msgtype)
        self._sequence[(topic, publisher)] = 0
        return channel_id

    def write(
        self, topic: str, msg: msgs.Message, log_time_ns: int, *, publisher: str = "sim"
    ) -> None:
        """Append ``msg`` on ``topic`` at sim time ``log_time_ns`` (never earlier than the last).

        ``publisher`` (``sim``, ``mission``, ``recorder``) names who published it: each gets
        its own channel of the topic (``/tf`` has both the simulator's and the mission's), so
        replay tells inputs from outputs by the channel, whatever frames a mission broadcasts.
        """
        self.write_raw(topic, type(msg).__msgtype__, encode(msg), log_time_ns, publisher=publisher)

    def write_raw(
        self, topic: str, msgtype: str, data: bytes, log_time_ns: int, *, publisher: str = "sim"
    ) -> None:
        """Append already-serialised CDR ``data`` (from a mission process, or a copied log)."""
        if self.closed:
            raise ValueError("write to a closed BagWriter")
        if log_time_ns < self._last_time:
            raise ValueError(
                f"log time went backwards on {topic}: {log_time_ns} < {self._last_time}"
            )
        if log_time_ns <= 0:
            raise ValueError("log times must be positive (some tools mishandle 0)")
        channel_id = self._channel(topic, msgtype, publisher)
        seq = self._sequence[(topic, publisher)]
        self._sequence[(topic, publisher)] = seq + 1
        self._writer.add_message(
            channel_id=channel_id,
            log_time=log_time_ns,
            data=data,
            publish_time=log_time_ns,
            sequence=seq,
        )
        self._last_time = log_time_ns
        self.message_count += 1

    def add_metadata(self, name: str, data: Mapping[str, str]) -> None:
        """A metadata record (string map), e.g. the run's settings."""
        self._writer.add_metadata(name=name, data=dict(sorted(data.items())))

    def add_attachment(self, name: str, media_type: str, data: bytes, log_time_ns: int = 0) -> None:
        """An attached file, e.g. ``scenario.toml``; create time = log time = sim time."""
        t = max(log_time_ns, 0)
        self._writer.add_attachment(
            create_time=t, log_time=t, name=name, media_type=media_type, data=data
        )

    def close(
        self,
        status: str = "complete",
        reason: str = "",
        *,
        outcome: str = "",
        outcome_reason: str = "",
    ) -> Path:
        """Write the status record, the summary and indexes; rename ``.part`` to the final name.

        ``status`` is the file's state; ``outcome`` how the run ended (``done``, ``time_limit``,
        ``crashed``, ...: set :attr:`outcome` while writing, or pass it here)."""
        if self.closed:
            return self.path
        self.closed = True
        try:
            self._writer.add_metadata(
                name=STATUS_METADATA,
                data={
                    "status": status,
                    "reason": reason,
                    "outcome": outcome,
                    "outcome_reason": outcome_reason,
                    "message_count": str(self.message_count),
                    "end_time_ns": str(self._last_time),
                },
            )
            self._writer.finish()  # type: ignore[no-untyped-call]
        finally:
            self._file.close()
        os.replace(self.part_path, self.path)
        return self.path


# --- reading ------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class BagMessage:
    """One logged message: topic, type, sim time, the CDR bytes, and (when asked) the value."""

    topic: str
    msgtype: str
    log_time_ns: int
    data: bytes
    msg: msgs.Message | None = None
    publisher: str = ""
    """Who published it (the channel's ``usar.publisher``): ``sim``, ``mission``, ``recorder``."""


@dataclass(frozen=True, slots=True)
class TopicInfo:
    """What ``usar info`` prints per topic."""

    topic: str
    msgtype: str
    count: int


@dataclass(slots=True)
class Damage:
    """How far a damaged (truncated or corrupt) log could be read."""

    reason: str
    messages_read: int = 0
    last_time_ns: int = 0

    def describe(self) -> str:
        """One line for a person."""
        return (
            f"{self.reason}; read {self.messages_read} messages up to sim time "
            f"{self.last_time_ns / 1e9:.3f} s"
        )


@dataclass(slots=True)
class _Index:
    topics: dict[str, TopicInfo] = field(default_factory=dict)
    start_ns: int = 0
    end_ns: int = 0
    metadata: dict[str, dict[str, str]] = field(default_factory=dict)
    attachments: dict[str, bytes] = field(default_factory=dict)


class BagReader:
    """Reads a usar log (or any ROS 2 MCAP whose types usar-replay knows).

    ``BagReader(path)`` checks that the file exists and is MCAP, and reads its summary. When the
    summary is missing (a truncated file) it scans the file once, streaming, to learn what is
    there; :attr:`damage` then says how far the file could be read and :attr:`complete` is False.
    """

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = Path(path)
        if not self.path.exists():
            raise NotAnMcapFile(f"{self.path}: no such file; check the path")
        if self.path.is_dir():
            raise NotAnMcapFile(f"{self.path}: is a directory, not an .mcap file")
        size = self.path.stat().st_size
        if size == 0:
            raise NotAnMcapFile(f"{self.path}: the file is empty; record a run with `usar record`")
        with open(self.path, "rb") as f:
            magic = f.read(len(MCAP_MAGIC))
        if magic != MCAP_MAGIC:
            raise NotAnMcapFile(
                f"{self.path}: not an MCAP file (bad magic); expected a log from `usar record`"
            )
        self.size_bytes = size
        self.damage: Damage | None = None
        self.has_summary = False
        self._index = self._read_summary() or self._scan()

    # -- summary -----------------------------------------------------------------------------

    def _read_summary(self) -> _Index | None:
        try:
            with open(self.path, "rb") as f:
                reader = SeekingReader(f)
                summary = reader.get_summary()
                if summary is None or summary.statistics is None:
                    return None
                stats = summary.statistics
                idx = _Index(start_ns=stats.message_start_time, end_ns=stats.message_end_time)
                for cid, ch in sorted(summary.channels.items()):
                    schema = summary.schemas.get(ch.schema_id)
                    name = schema.name if schema else ""
                    count = stats.channel_message_counts.get(cid, 0)
                    prior = idx.topics.get(ch.topic)
                    total = count + (prior.count if prior else 0)
                    idx.topics[ch.topic] = TopicInfo(ch.topic, name, total)
                for md in reader.iter_metadata():
                    idx.metadata[md.name] = dict(md.metadata)
                for att in reader.iter_attachments():
                    idx.attachments[att.name] = bytes(att.data)
        except Exception:  # noqa: BLE001 - mcap raises assorted errors on a bad footer: no summary
            return None
        self.has_summary = True
        return idx

    def _scan(self) -> _Index:
        idx = _Index()
        counts: dict[str, int] = {}
        types: dict[str, str] = {}
        first = True
        for rec in self._stream_records():
            if isinstance(rec, _Msg):
                counts[rec.topic] = counts.get(rec.topic, 0) + 1
                types[rec.topic] = rec.msgtype
                if first:
                    idx.start_ns, first = rec.log_time, False
                idx.end_ns = rec.log_time
            elif isinstance(rec, Metadata):
                idx.metadata[rec.name] = dict(rec.metadata)
            elif isinstance(rec, Attachment):
                idx.attachments[rec.name] = bytes(rec.data)
        for topic in sorted(counts):
            idx.topics[topic] = TopicInfo(topic, types[topic], counts[topic])
        if self.damage is None:
            self.damage = Damage("the file has no summary (it was not closed)")
        self.damage.messages_read = sum(counts.values())
        self.damage.last_time_ns = idx.end_ns
        return idx

    def _stream_records(self) -> Iterator[Any]:
        """Every record in file order, chunks expanded; stops (and notes why) at damage."""
        schemas: dict[int, Schema] = {}
        channels: dict[int, Channel] = {}
        with open(self.path, "rb") as f:
            stream = StreamReader(io.BufferedReader(f), skip_magic=False)
            try:
                for rec in stream.records:
                    inner: Iterable[Any] = breakup_chunk(rec) if isinstance(rec, Chunk) else (rec,)
                    for r in inner:
                        if isinstance(r, Schema):
                            schemas[r.id] = r
                        elif isinstance(r, Channel):
                            channels[r.id] = r
                        elif isinstance(r, McapMessage):
                            ch = channels[r.channel_id]
                            schema = schemas.get(ch.schema_id)
                            yield _Msg(
                                ch.topic,
                                schema.name if schema else "",
                                r,
                                ch.metadata.get(PUBLISHER_KEY, ""),
                            )
                        else:
                            yield r
            except Exception as err:  # noqa: BLE001 - any decode failure means: damaged here
                prior = self.damage
                self.damage = Damage(f"the file is truncated or corrupt ({_short(err)})")
                if prior is not None:
                    self.damage.messages_read = prior.messages_read
                    self.damage.last_time_ns = prior.last_time_ns

    # -- public view -------------------------------------------------------------------------

    @property
    def complete(self) -> bool:
        """True when the file has its summary and was closed as ``complete``."""
        return self.has_summary and self.status == "complete"

    @property
    def status(self) -> str:
        """``complete``, ``interrupted``, ``truncated`` (no summary), or ``unknown``."""
        if not self.has_summary:
            return "truncated"
        return self._index.metadata.get(STATUS_METADATA, {}).get("status", "unknown")

    @property
    def topics(self) -> dict[str, TopicInfo]:
        """Topic -> (type, message count), sorted by topic name."""
        return dict(sorted(self._index.topics.items()))

    @property
    def start_ns(self) -> int:
        return self._index.start_ns

    @property
    def end_ns(self) -> int:
        return self._index.end_ns

    @property
    def message_count(self) -> int:
        return sum(t.count for t in self._index.topics.values())

    @property
    def metadata(self) -> dict[str, dict[str, str]]:
        """Metadata records by name (the run settings, the status)."""
        return dict(self._index.metadata)

    @property
    def attachments(self) -> dict[str, bytes]:
        """Attached files by name (``scenario.toml``)."""
        return dict(self._index.attachments)

    def messages(
        self,
        topics: Iterable[str] | None = None,
        start_ns: int | None = None,
        end_ns: int | None = None,
        *,
        decode_messages: bool = True,
    ) -> Iterator[BagMessage]:
        """Messages in log-time order, filtered by topic and ``[start_ns, end_ns)``; streaming.

        A damaged file yields what it holds up to the damage and sets :attr:`damage`; the caller
        decides whether that is an error (the CLI reports it and exits 3).
        """
        wanted = None if topics is None else set(topics)
        if self.has_summary:
            yield from self._messages_indexed(wanted, start_ns, end_ns, decode_messages)
            return
        count, last = 0, 0
        for rec in self._stream_records():
            if not isinstance(rec, _Msg):
                continue
            t = rec.log_time
            count, last = count + 1, t
            if self.damage is not None:
                self.damage.messages_read, self.damage.last_time_ns = count, last
            if wanted is not None and rec.topic not in wanted:
                continue
            if (start_ns is not None and t < start_ns) or (end_ns is not None and t >= end_ns):
                continue
            yield _bag_message(rec.topic, rec.msgtype, t, rec.data, decode_messages, rec.publisher)

    def _messages_indexed(
        self, wanted: set[str] | None, start_ns: int | None, end_ns: int | None, dec: bool
    ) -> Iterator[BagMessage]:
        count, last = 0, 0
        with open(self.path, "rb") as f:
            reader = SeekingReader(f)
            try:
                it = reader.iter_messages(
                    topics=None if wanted is None else sorted(wanted),
                    starting_at=start_ns,
                    ending_before=end_ns,
                    log_time_order=True,
                )
                for schema, channel, message in it:
                    msgtype = schema.name if schema else ""
                    out = _bag_message(
                        channel.topic,
                        msgtype,
                        message.log_time,
                        message.data,
                        dec,
                        channel.metadata.get(PUBLISHER_KEY, ""),
                    )
                    count, last = count + 1, message.log_time
                    yield out
            except Exception as err:  # noqa: BLE001 - zstd and struct errors from a bad chunk
                self.damage = Damage(f"the file is corrupt ({_short(err)})", count, last)


@dataclass(frozen=True, slots=True)
class _Msg:
    topic: str
    msgtype: str
    record: McapMessage
    publisher: str = ""

    @property
    def log_time(self) -> int:
        return int(self.record.log_time)

    @property
    def data(self) -> bytes:
        return bytes(self.record.data)


def _bag_message(
    topic: str, msgtype: str, t: int, data: bytes, dec: bool, publisher: str = ""
) -> BagMessage:
    value: msgs.Message | None = None
    if dec:
        try:
            value = decode(bytes(data), msgtype)
        except KeyError:
            value = None  # a type usar-replay does not know: keep the bytes only
        except Exception as err:
            raise LogError(
                f"message on {topic} at {t / 1e9:.3f} s cannot be decoded: {err}"
            ) from err
    return BagMessage(topic, msgtype, int(t), bytes(data), value, publisher)


def _short(err: BaseException) -> str:
    text = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
    return text[:120]
