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
* **Camera frames in chunks of their own** (``BagWriter(image_chunks=True)``): a reader that
  asks for other topics (``usar grade``) then skips the image chunks by the chunk indexes'
  message-index offsets and never decompresses them. The two kinds of chunk are finished
  together, at a log-time boundary, non-image chunk first: each pair covers its own time
  window, so log-time order across pairs is file order, and within one sim time a log-time
  ordered read (mcap breaks ties by chunk offset) yields that time's non-image messages, then
  its image. That is a change of order at equal times for messages written *after* the image at
  the same time, hence opt-in: the recorder must make the image the last input of its tick.
* Log time = publish time = sim time in nanoseconds. Log times never go backwards in a usar log
  (the writer refuses), so file order is time order even when the summary is lost.
"""

from __future__ import annotations

import functools
import io
import os
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

import numpy as np
from mcap._chunk_builder import ChunkBuilder
from mcap.reader import SeekingReader
from mcap.records import Attachment, Channel, Chunk, Metadata, Schema
from mcap.records import Message as McapMessage
from mcap.stream_reader import StreamReader, breakup_chunk
from mcap.writer import CompressionType, Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore

from usar_replay import __version__, msgs
from usar_replay.contract import IMAGE
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
STATUS_METADATA = "usar.status"
"""Metadata record written on close: ``status`` is ``complete`` or ``interrupted``."""
RUN_METADATA = "usar.run"
"""Metadata record with the run's settings and software version (written by the recorder)."""
MCAP_MAGIC = b"\x89MCAP0\r\n"

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


LATCHED_TOPICS = frozenset({"/tf_static", "/explorer/camera/rgb/camera_info_static"})
"""Topics written with transient-local QoS, as a latched ROS 2 publisher offers them."""


# --- CDR via rosbags' typestore -----------------------------------------------------------------


@functools.cache
def typestore() -> Typestore:
    """A rosbags typestore holding exactly the definitions declared in :mod:`usar_replay.msgs`."""
    store = get_typestore(Stores.EMPTY)
    for cls in msgs.MESSAGE_TYPES:
        store.register(get_types_from_msg(cls.__msgdef__, cls.__msgtype__))
    return store


@functools.cache
def schema_text(msgtype: str) -> str:
    """The ``ros2msg`` schema of a type: its definition followed by every dependency's."""
    text, _ = typestore().generate_msgdef(msgtype, ros_version=2)
    return text


def _to_ros(value: msgs.Message, store: Typestore) -> Any:
    cls = type(value)
    kwargs: dict[str, Any] = {}
    for name, kind, _ in msgs.field_kinds(cls):
        v = getattr(value, name)
        if kind == "msg":
            kwargs[name] = _to_ros(v, store)
        elif kind == "msgs":
            kwargs[name] = [_to_ros(x, store) for x in v]
        elif kind == "bytes":
            kwargs[name] = np.frombuffer(v, dtype=np.uint8)
        elif kind == "floats":
            kwargs[name] = np.asarray(v, dtype=np.float64)
        else:
            kwargs[name] = v
    return store.types[cls.__msgtype__](**kwargs)


def _from_ros(obj: Any, cls: type[msgs.Message]) -> msgs.Message:
    kwargs: dict[str, Any] = {}
    for name, kind, elem in msgs.field_kinds(cls):
        v = getattr(obj, name)
        if kind == "msg":
            kwargs[name] = _from_ros(v, elem)
        elif kind == "msgs":
            kwargs[name] = tuple(_from_ros(x, elem) for x in v)
        elif kind == "bytes":
            kwargs[name] = bytes(v)
        elif kind == "floats":
            kwargs[name] = tuple(float(x) for x in v)
        elif kind == "float":
            kwargs[name] = float(v)
        elif kind == "int":
            kwargs[name] = int(v)
        elif kind == "bool":
            kwargs[name] = bool(v)
        else:
            kwargs[name] = str(v)
    return cls(**kwargs)


def encode(msg: msgs.Message) -> bytes:
    """CDR bytes of a message, exactly as they are written to the log."""
    store = typestore()
    return bytes(store.serialize_cdr(_to_ros(msg, store), type(msg).__msgtype__))


def decode(data: bytes, msgtype: str) -> msgs.Message:
    """The typed message of CDR ``data`` of ROS 2 type ``msgtype`` (``pkg/msg/Type``)."""
    cls = msgs.message_class(msgtype)
    return _from_ros(typestore().deserialize_cdr(data, msgtype), cls)


# --- writing ------------------------------------------------------------------------------------


_BUILDER = "_Writer__chunk_builder"
_FINALIZE = "_Writer__finalize_chunk"
"""mcap 1.x's Writer keeps its open chunk in a private attribute; :class:`_PairedWriter` swaps
it (tests/test_bag.py checks the layout this gives, so an mcap that changes it fails there)."""


class _PairedWriter(Writer):
    """An mcap ``Writer`` with two open chunks, one for image topics and one for the rest.

    Chunks are finished only by :meth:`finish_pair` (both, non-image first) or at the end, never
    by the base class (its size limit is set out of reach): the caller decides, at log-time
    boundaries, so that each pair of chunks covers its own time window.
    """

    def __init__(self, stream: IO[bytes], compression: CompressionType) -> None:
        super().__init__(stream, chunk_size=1 << 62, compression=compression)
        self._builders: dict[bool, ChunkBuilder] = {
            False: getattr(self, _BUILDER),
            True: ChunkBuilder(),
        }
        self._schema_in: dict[bool, set[int]] = {False: set(), True: set()}

    def use(self, images: bool) -> None:
        """Route what is added next (schemas, channels, messages) to that kind's chunk."""
        setattr(self, _BUILDER, self._builders[images])

    def builder_size(self, images: bool) -> int:
        return int(self._builders[images].count)

    def schema_into(self, images: bool, schema: Schema) -> None:
        """Make sure the chunk of this kind holds ``schema`` before a channel of it (a stream
        reader of a file without its summary resolves channels from records seen earlier)."""
        if schema.id not in self._schema_in[images]:
            self._builders[images].add_schema(schema)
            self._schema_in[images].add(schema.id)

    def finish_pair(self) -> None:
        """Write both open chunks (non-image first) and start new ones."""
        current = getattr(self, _BUILDER)
        for images in (False, True):
            setattr(self, _BUILDER, self._builders[images])
            getattr(self, _FINALIZE)()
        self._schema_in = {False: set(), True: set()}
        setattr(self, _BUILDER, current)

    def finish(self) -> None:
        self.finish_pair()
        self.use(False)
        super().finish()  # type: ignore[no-untyped-call]


class BagWriter:
    """Writes a usar log: one MCAP file, ``ros2`` profile, zstd chunks, indexes and summary.

    Use as a context manager. Leaving the block normally closes the file as ``complete``; leaving
    it by ``KeyboardInterrupt`` closes it as ``interrupted`` (still indexed and readable) and lets
    the interrupt go on; any other exception also closes the file, marked ``interrupted`` with the
    error's text, so a crash loses nothing that was already written.

    ``image_chunks=True`` writes the ``image_topics`` in chunks of their own (see the module's
    notes for the order this gives at equal log times); ``chunk_size`` then bounds each kind.
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        *,
        chunk_size: int = 1 << 20,
        compression: str = "zstd",
        image_chunks: bool = False,
        image_topics: Iterable[str] = (IMAGE,),
    ) -> None:
        self.path = Path(path)
        self.part_path = self.path.with_name(self.path.name + ".part")
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._file: IO[bytes] = open(self.part_path, "wb")  # noqa: SIM115 - closed in close()
        comp = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4}.get(compression)
        if comp is None:
            comp = CompressionType.NONE
        self._paired: _PairedWriter | None = None
        if image_chunks:
            self._paired = _PairedWriter(self._file, comp)
            self._writer: Writer = self._paired
        else:
            self._writer = Writer(self._file, chunk_size=chunk_size, compression=comp)
        self._chunk_size = chunk_size
        self._image_topics = frozenset(image_topics)
        self._writer.start(profile=PROFILE, library=f"usar-replay/{__version__}")
        self._schemas: dict[str, Schema] = {}
        self._channels: dict[str, tuple[int, str]] = {}
        self._sequence: dict[str, int] = {}
        self._last_time = 0
        self.message_count = 0
        self.closed = False

    def __enter__(self) -> BagWriter:
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: Any
    ) -> None:
        if self.closed:
            return
        if exc_type is None:
            self.close("complete")
        elif issubclass(exc_type, KeyboardInterrupt):
            self.close("interrupted", reason="interrupted by the user (Ctrl-C)")
        else:
            self.close("interrupted", reason=f"{exc_type.__name__}: {exc}")

    def _channel(self, topic: str, msgtype: str) -> int:
        known = self._channels.get(topic)
        if known is not None:
            if known[1] != msgtype:
                raise ValueError(f"topic {topic} has type {known[1]}, cannot write {msgtype}")
            return known[0]
        schema = self._schemas.get(msgtype)
        if schema is None:
            text = schema_text(msgtype).encode()
            if self._paired is not None:
                self._paired.use(topic in self._image_topics)
            schema_id = self._writer.register_schema(
                name=msgtype, encoding=SCHEMA_ENCODING, data=text
            )
            schema = Schema(id=schema_id, name=msgtype, encoding=SCHEMA_ENCODING, data=text)
            self._schemas[msgtype] = schema
            if self._paired is not None:
                self._paired.schema_into(topic in self._image_topics, schema)
        elif self._paired is not None:
            self._paired.schema_into(topic in self._image_topics, schema)
        qos = _qos_yaml(transient_local=topic in LATCHED_TOPICS)
        if self._paired is not None:
            self._paired.use(topic in self._image_topics)
        channel_id = self._writer.register_channel(
            topic=topic,
            message_encoding=MESSAGE_ENCODING,
            schema_id=schema.id,
            metadata={"offered_qos_profiles": qos},
        )
        self._channels[topic] = (channel_id, msgtype)
        self._sequence[topic] = 0
        return channel_id

    def write(self, topic: str, msg: msgs.Message, log_time_ns: int) -> None:
        """Append ``msg`` on ``topic`` at sim time ``log_time_ns`` (never earlier than the last)."""
        self.write_raw(topic, type(msg).__msgtype__, encode(msg), log_time_ns)

    def write_raw(self, topic: str, msgtype: str, data: bytes, log_time_ns: int) -> None:
        """Append already-serialised CDR ``data`` (used when copying or editing a log)."""
        if self.closed:
            raise ValueError("write to a closed BagWriter")
        if log_time_ns < self._last_time:
            raise ValueError(
                f"log time went backwards on {topic}: {log_time_ns} < {self._last_time}"
            )
        if log_time_ns <= 0:
            raise ValueError("log times must be positive (some tools mishandle 0)")
        paired = self._paired
        if paired is not None and log_time_ns > self._last_time:
            limit = self._chunk_size
            if paired.builder_size(False) > limit or paired.builder_size(True) > limit:
                paired.finish_pair()  # only between two log times: the windows never overlap
        channel_id = self._channel(topic, msgtype)
        if paired is not None:
            paired.use(topic in self._image_topics)
        seq = self._sequence[topic]
        self._sequence[topic] = seq + 1
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

    def close(self, status: str = "complete", reason: str = "") -> Path:
        """Write the status record, the summary and indexes; rename ``.part`` to the final name."""
        if self.closed:
            return self.path
        self.closed = True
        try:
            self._writer.add_metadata(
                name=STATUS_METADATA,
                data={
                    "status": status,
                    "reason": reason,
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
                    idx.topics[ch.topic] = TopicInfo(ch.topic, name, count)
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
            stream = StreamReader(io.BufferedReader(f), skip_magic=False)  # type: ignore[arg-type]
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
                            yield _Msg(ch.topic, schema.name if schema else "", r)
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
            yield _bag_message(rec.topic, rec.msgtype, t, rec.data, decode_messages)

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
                    out = _bag_message(channel.topic, msgtype, message.log_time, message.data, dec)
                    count, last = count + 1, message.log_time
                    yield out
            except Exception as err:  # noqa: BLE001 - zstd and struct errors from a bad chunk
                self.damage = Damage(f"the file is corrupt ({_short(err)})", count, last)


@dataclass(frozen=True, slots=True)
class _Msg:
    topic: str
    msgtype: str
    record: McapMessage

    @property
    def log_time(self) -> int:
        return int(self.record.log_time)

    @property
    def data(self) -> bytes:
        return bytes(self.record.data)


def _bag_message(topic: str, msgtype: str, t: int, data: bytes, dec: bool) -> BagMessage:
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
    return BagMessage(topic, msgtype, int(t), bytes(data), value)


def _short(err: BaseException) -> str:
    text = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
    return text[:120]
