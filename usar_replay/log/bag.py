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

import contextlib
import errno
import fcntl
import os
from collections.abc import Callable, Collection, Iterable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

from usar_replay import __version__
from usar_replay.core import contract, msgs, ros1msg
from usar_replay.core.cdr import decode, encode, schema_text, typestore
from usar_replay.core.errors import LogError, NotAnMcapFile, UsageError
from usar_replay.log import mcapfile

if TYPE_CHECKING:
    from mcap.writer import Writer

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
PUBLISHER_KEY = mcapfile.PUBLISHER_KEY
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


# --- CDR lives in usar_replay.core.cdr (re-exported here for older callers) ---------------------


@dataclass(frozen=True, slots=True)
class _Watcher:
    """One :meth:`BagWriter.watch`: the topics, their allowed publishers, the callback."""

    topics: frozenset[str]
    only_from: Mapping[str, Collection[str]]
    callback: Callable[[str, msgs.Message | None, int], None]


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
        # imported here: reading a log (grade, info, view) never needs the writer's imports
        from mcap.writer import CompressionType, Writer

        self.path = Path(path)
        self.part_path = self.path.with_name(self.path.name + ".part")
        self._file: IO[bytes] = _open_part(self.part_path)
        self._existing = _identity(self.path)
        """The file at the output path when we started (None: none); replaced at close only if it
        is still that file (the caller allowed it: ``--overwrite``)."""
        comp = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4}.get(compression)
        if comp is None:
            comp = CompressionType.NONE
        # data CRCs on: a reader can check every byte of the file, not only the chunks
        self._writer: Writer = Writer(
            self._file, chunk_size=chunk_size, compression=comp, enable_data_crcs=True
        )
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
        self._watchers: list[_Watcher] = []

    def watch(
        self,
        topics: Iterable[str],
        callback: Callable[[str, msgs.Message | None, int], None],
        *,
        only_from: Mapping[str, Collection[str]] | None = None,
    ) -> None:
        """From now on, ``callback(topic, value, log time)`` for every message written on
        ``topics``, in write order, decoded from the written bytes: what
        :meth:`BagReader.decoded` (same ``only_from``) will give of the finished file, as it is
        written (``usar record`` grades while it records)."""
        self._watchers.append(_Watcher(frozenset(topics), dict(only_from or {}), callback))

    @property
    def topics(self) -> frozenset[str]:
        """The topics written so far."""
        return frozenset(topic for topic, _ in self._channels)

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
            # str() of a plain KeyboardInterrupt is empty; signals.Terminated names its signal
            reason = str(exc) or "interrupted by the user (Ctrl-C)"
            self.close("interrupted", reason=reason, outcome="interrupted", outcome_reason=reason)
        elif isinstance(exc, OSError) and exc.errno in _DISK_ERRORS:
            raise self._disk_failure(exc) from exc
        else:
            reason = f"{exc_type.__name__}: {exc}"
            self.close("interrupted", reason=reason, outcome="interrupted", outcome_reason=reason)

    def _disk_failure(self, err: OSError) -> UsageError:
        """The disk filled (or failed) while recording: keep what was written, say how to save
        it. Closing would need more space, so the ``.part`` is left for ``usar recover``."""
        with contextlib.suppress(OSError):
            self._file.close()
        self.closed = True
        what = "the disk is full" if err.errno == errno.ENOSPC else f"cannot write ({err.strerror})"
        if self.message_count == 0:
            with contextlib.suppress(OSError):
                self.part_path.unlink()
            return UsageError(f"{self.path}: {what}; nothing was recorded; free some space")
        return UsageError(
            f"{self.path}: {what} after {self.message_count} messages; free some space, then "
            f"`usar recover {self.part_path}` saves them as a log"
        )

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
        for w in self._watchers:
            if topic in w.topics and publisher in w.only_from.get(topic, (publisher,)):
                w.callback(topic, _decoded(topic, msgtype, log_time_ns, data), log_time_ns)

    def write_ros1(
        self, topic: str, message: ros1msg.Ros1Message, log_time_ns: int, *, publisher: str
    ) -> None:
        """Append a ROS 1 message as it was on the wire: a channel in MCAP's ``ros1`` message
        encoding with a ``ros1msg`` schema named ``pkg/Type`` (:mod:`usar_replay.core.ros1msg`;
        Foxglove reads it), for a type usar has no ROS 2 value for."""
        key = (topic, publisher)
        if key not in self._channels:
            schema_key = f"{message.msgtype}\n{message.definition}"
            schema_id = self._schemas.get(schema_key)
            if schema_id is None:
                schema_id = self._writer.register_schema(
                    name=message.msgtype,
                    encoding=ros1msg.SCHEMA_ENCODING,
                    data=message.definition.encode(),
                )
                self._schemas[schema_key] = schema_id
            channel_id = self._writer.register_channel(
                topic=topic,
                message_encoding=ros1msg.MESSAGE_ENCODING,
                schema_id=schema_id,
                metadata={PUBLISHER_KEY: publisher},
            )
            self._channels[key] = (channel_id, message.msgtype)
            self._sequence[key] = 0
        self.write_raw(topic, message.msgtype, message.data, log_time_ns, publisher=publisher)

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
        ``crashed``, ...: set :attr:`outcome` while writing, or pass it here).

        A file that appeared at the final name while we wrote (another program, a second
        recording) is never replaced: the log is kept under a free name beside it
        (``NAME.2.mcap``) and :class:`UsageError` says where. Returns the final path.
        """
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
            self._file.flush()
        except OSError as err:
            raise self._disk_failure(err) from err
        finally:
            with contextlib.suppress(OSError):
                self._file.close()
        now = _identity(self.path)
        if now is not None and now != self._existing:
            kept = _free_name(self.path)
            _link_or_rename(self.part_path, kept)
            raise UsageError(
                f"{self.path} appeared while recording and was left as it is; this recording "
                f"was saved as {kept}"
            )
        if now is None:
            try:
                _link_or_rename(self.part_path, self.path)
            except FileExistsError:  # it appeared in the last instant
                kept = _free_name(self.path)
                _link_or_rename(self.part_path, kept)
                raise UsageError(
                    f"{self.path} appeared while recording and was left as it is; this "
                    f"recording was saved as {kept}"
                ) from None
        else:
            os.replace(self.part_path, self.path)
        return self.path


def _open_part(part: Path) -> IO[bytes]:
    """Create ``part`` exclusively and hold a lock on it while the log is written.

    Two recordings to one output must not both proceed (they corrupted each other): the second
    finds the ``.part`` and is refused. A ``.part`` nobody holds is what a killed recording left:
    it is refused too, since it may be all that is left of a run (``usar recover`` saves it).
    """
    try:
        part.parent.mkdir(parents=True, exist_ok=True)
        fd = os.open(part, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
    except FileExistsError:
        if _locked(part):
            raise UsageError(
                f"{part}: another `usar record` is writing this output now; wait for it or "
                "choose another --out"
            ) from None
        raise UsageError(
            f"{part}: left by a recording that was killed; `usar recover {part}` saves what it "
            "holds (or delete it), then record again"
        ) from None
    except OSError as err:
        raise _write_error(part, err) from err
    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    return os.fdopen(fd, "wb")


def _locked(part: Path) -> bool:
    try:
        fd = os.open(part, os.O_RDONLY)
    except OSError:
        return True  # unreadable or gone: treat as in use, the safe answer
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        return True
    finally:
        os.close(fd)
    return False


def _write_error(p: Path, err: OSError) -> UsageError:
    if err.errno == errno.ENOSPC:
        return UsageError(f"{p}: the disk is full; free some space and run again")
    if err.errno in (errno.EACCES, errno.EPERM, errno.EROFS):
        return UsageError(f"{p}: cannot write here (permission denied); choose another --out")
    return UsageError(f"{p}: cannot write: {err.strerror or err}")


_DISK_ERRORS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EIO, errno.EROFS})


def _identity(p: Path) -> tuple[int, int, int] | None:
    try:
        st = p.stat()
    except OSError:
        return None
    return (st.st_dev, st.st_ino, st.st_mtime_ns)


def _free_name(p: Path) -> Path:
    for k in range(2, 10_000):
        candidate = p.with_name(f"{p.stem}.{k}{p.suffix}")
        if not candidate.exists() and not candidate.with_name(candidate.name + ".part").exists():
            return candidate
    raise UsageError(f"{p}: no free name beside it")  # pragma: no cover


def _link_or_rename(src: Path, dst: Path) -> None:
    """Give ``src`` the name ``dst`` without ever replacing a file there (FileExistsError)."""
    try:
        os.link(src, dst)
    except FileExistsError:
        raise
    except OSError:  # a file system without hard links: check, then rename (a small window)
        if dst.exists():
            raise FileExistsError(dst) from None
        os.rename(src, dst)
        return
    src.unlink()


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
    """What is damaged in a log, and how much of it could still be read."""

    reason: str
    """What is damaged, for a person: ``chunk 12 of 80 (sim time 30.1-31.4 s) fails its CRC
    check``; several findings are joined with ``; ``."""
    messages_read: int = 0
    """Messages that can still be read (all of them when only a header or attachment is hit)."""
    last_time_ns: int = 0
    messages_total: int | None = None
    """How many messages the file's summary says it holds (None without a summary)."""

    def describe(self) -> str:
        """One line for a person: what is damaged, then what was recovered."""
        of = ""
        if self.messages_total is not None and self.messages_total > 0:
            share = self.messages_read / self.messages_total
            of = f" ({share:.1%} of {self.messages_total})"
        return (
            f"{self.reason}; read {self.messages_read} messages up to sim time "
            f"{self.last_time_ns / 1e9:.3f} s{of}"
        )


CHECKS = ("summary", "data", "full")
"""How much :class:`BagReader` checks when it opens a file: ``summary`` trusts the summary (fast,
``usar info --quick``); ``data`` (the default) also checks the data CRC over the whole file, the
header and the attachments' CRCs (decompressing every chunk only when that CRC fails, to find
which are damaged); ``full`` decompresses and checks every chunk (``usar info``). Whatever the
level, every chunk that :meth:`BagReader.messages` reads is CRC-checked."""


class BagReader:
    """Reads a usar log (or any ROS 2 MCAP whose types usar-replay knows), checking it.

    ``BagReader(path)`` checks that the file exists and is MCAP, reads its summary and checks the
    data against it (see :data:`CHECKS`). When the summary is missing or damaged (a killed
    recorder, a partial copy) it scans the file once, streaming, checking every chunk.
    :attr:`damage` then says what is damaged and how much can still be read; :meth:`messages`
    yields every message of every intact chunk (skipping damaged ones) and never raises for a
    damaged file. Chunks read by :meth:`messages` are always CRC-checked.
    """

    def __init__(self, path: str | os.PathLike[str], *, check: str = "data") -> None:
        if check not in CHECKS:
            raise ValueError(f"check must be one of {CHECKS}")
        self.path = Path(path)
        if not self.path.exists():
            raise UsageError(f"{self.path}: no such file; check the path")
        if self.path.is_dir():
            raise UsageError(f"{self.path}: is a directory, not an .mcap file")
        try:
            with open(self.path, "rb") as f:
                magic = f.read(len(mcapfile.MAGIC))
                size = os.fstat(f.fileno()).st_size
                if size == 0:
                    raise NotAnMcapFile(
                        f"{self.path}: the file is empty; record a run with `usar record`"
                    )
                if magic != mcapfile.MAGIC:
                    raise NotAnMcapFile(
                        f"{self.path}: not an MCAP file (bad magic); expected a log from "
                        "`usar record`"
                    )
                self.size_bytes = size
                self.damage: Damage | None = None
                layout = mcapfile.read_summary(f, size)
                self.has_summary = layout is not None
                if layout is None:
                    layout = mcapfile.scan(f, size)
                    self._layout = layout
                    self.damage = self._scan_damage()
                else:
                    self._layout = layout
                    self.damage = self._check(f, check)
        except PermissionError as err:
            raise UsageError(f"{self.path}: cannot read the file (permission denied)") from err
        except IsADirectoryError as err:  # pragma: no cover - raced with the check above
            raise UsageError(f"{self.path}: is a directory, not an .mcap file") from err
        self.part = self.path.name.endswith(".part")

    # -- checks ------------------------------------------------------------------------------

    def _scan_damage(self) -> Damage:
        lay = self._layout
        why = [*lay.problems]
        bad = [c for c in lay.chunks if c.problem]
        why += [c.problem for c in bad[:2]]
        if len(bad) > 2:
            why.append(f"{len(bad) - 2} more chunks are damaged")
        if lay.stopped_at is not None and not any(p.startswith("the header") for p in why):
            why.insert(
                0,
                "the file is truncated (no summary: the recorder was killed or the copy is "
                f"partial); readable up to byte {lay.stopped_at} of {self.size_bytes}",
            )
        elif lay.stopped_at is None:
            why.insert(0, "the file's summary (its index) is missing or damaged")
        good = sum(c.message_count or 0 for c in lay.chunks if not c.problem)
        last = max((c.end_ns for c in lay.chunks if not c.problem), default=0)
        return Damage("; ".join(why), good, last)

    def _check(self, f: IO[bytes], check: str) -> Damage | None:
        lay = self._layout
        why = [*lay.problems]
        if check == "summary":
            return Damage("; ".join(why), *self._totals()) if why else None
        header = mcapfile.header_problem(f, self.size_bytes)
        if header:
            why.append(header)
        crc_ok = mcapfile.data_crc_matches(f, lay)
        if check == "full" or crc_ok is False:
            for ref in lay.chunks:
                try:
                    for _ in mcapfile.chunk_messages(f, ref, self.size_bytes, lay):
                        pass
                except mcapfile.Broken as err:
                    ref.problem = str(err)
            bad = [c for c in lay.chunks if c.problem]
            if bad:
                why.append(self._chunk_phrase(bad))
            elif crc_ok is False and not header:
                why.append(
                    "the data CRC fails: bytes outside the message chunks were changed "
                    "(metadata, attachments or indexes)"
                )
        if not why:
            return None
        return Damage("; ".join(why), *self._totals())

    def _chunk_phrase(self, bad: list[mcapfile.ChunkRef]) -> str:
        n = len(self._layout.chunks)
        first = bad[0]
        phrase = (
            f"chunk {first.number} of {n} (sim time {first.start_ns / 1e9:.1f}-"
            f"{first.end_ns / 1e9:.1f} s) is damaged: "
            + first.problem.removeprefix(f"chunk {first.number} ")
        )
        if len(bad) > 1:
            phrase += f"; {len(bad) - 1} more of the {n} chunks are damaged"
        return phrase

    def _totals(self) -> tuple[int, int, int | None]:
        """(messages readable, last readable time, messages in the file) for a summary file."""
        lay = self._layout
        total = lay.message_count
        bad = [c for c in lay.chunks if c.problem]
        if not bad:
            return total or 0, lay.end_ns, total
        lost = 0
        with open(self.path, "rb") as f:
            for c in bad:
                lost += mcapfile.indexed_count(f, c, self.size_bytes) or 0
        last = max((c.end_ns for c in lay.chunks if not c.problem), default=0)
        return max((total or 0) - lost, 0), last, total

    def _note_bad_chunk(self, ref: mcapfile.ChunkRef, problem: str) -> None:
        """A chunk found damaged while reading messages (not known when the file was opened)."""
        ref.problem = problem
        bad = [c for c in self._layout.chunks if c.problem]
        prior = self.damage.reason if self.damage is not None else ""
        parts = [p for p in prior.split("; ") if p and not p.startswith(("chunk ", "1 more"))]
        parts = [p for p in parts if "more of the" not in p]
        parts.append(self._chunk_phrase(bad))
        if self.has_summary:
            read, last, total = self._totals()
            self.damage = Damage("; ".join(parts), read, last, total)
        else:
            good = sum(c.message_count or 0 for c in self._layout.chunks if not c.problem)
            last = max((c.end_ns for c in self._layout.chunks if not c.problem), default=0)
            self.damage = Damage("; ".join(parts), good, last)

    # -- public view -------------------------------------------------------------------------

    @property
    def complete(self) -> bool:
        """True when the file has its summary, is undamaged and was closed as ``complete``."""
        return self.has_summary and self.damage is None and self.status == "complete"

    @property
    def status(self) -> str:
        """``complete``, ``interrupted``, ``truncated`` (no summary), or ``unknown``."""
        if not self.has_summary:
            return "truncated"
        return self._layout.metadata.get(STATUS_METADATA, {}).get("status", "unknown")

    @property
    def topics(self) -> dict[str, TopicInfo]:
        """Topic -> (type, message count), sorted by topic name."""
        lay = self._layout
        out: dict[str, TopicInfo] = {}
        for cid, ch in lay.channels.items():
            count = lay.channel_counts.get(cid, 0)
            if not self.has_summary and count == 0:
                continue
            prior = out.get(ch.topic)
            out[ch.topic] = TopicInfo(ch.topic, ch.msgtype, count + (prior.count if prior else 0))
        return dict(sorted(out.items()))

    @property
    def start_ns(self) -> int:
        return self._layout.start_ns

    @property
    def end_ns(self) -> int:
        return self._layout.end_ns

    @property
    def message_count(self) -> int:
        return sum(t.count for t in self.topics.values())

    @property
    def chunk_count(self) -> int:
        return len(self._layout.chunks)

    @property
    def data_crc_recorded(self) -> bool:
        """Whether the writer recorded a data CRC (logs before usar-replay 0.2 have none)."""
        return self._layout.data_crc != 0

    @property
    def metadata(self) -> dict[str, dict[str, str]]:
        """Metadata records by name (the run settings, the status)."""
        return dict(self._layout.metadata)

    @property
    def attachments(self) -> dict[str, bytes]:
        """Attached files by name (``scenario.toml``)."""
        return dict(self._layout.attachments)

    def messages(
        self,
        topics: Iterable[str] | None = None,
        start_ns: int | None = None,
        end_ns: int | None = None,
        *,
        decode_messages: bool = True,
    ) -> Iterator[BagMessage]:
        """Messages in log-time order, filtered by topic and ``[start_ns, end_ns)``; streaming.

        Every chunk read is decompressed and its CRC checked; a damaged chunk is skipped and
        noted in :attr:`damage` (the caller decides whether that is an error: the CLI reports it
        and exits 3). Messages are yielded in file order, which is log-time order in a usar log
        (the writer refuses times that go backwards).
        """
        window = start_ns is not None or end_ns is not None
        for found in self._chunks(topics, start_ns, end_ns):
            for info, t, data in found:
                if window and (
                    (start_ns is not None and t < start_ns) or (end_ns is not None and t >= end_ns)
                ):
                    continue
                yield _new_bag_message(
                    info.topic,
                    info.msgtype,
                    t,
                    data,
                    _decoded(info.topic, info.msgtype, t, data) if decode_messages else None,
                    info.publisher,
                )

    def ros1_definition(self, topic: str) -> tuple[str, str] | None:
        """(``pkg/Type``, full definition) of a topic kept in ROS 1's own encoding
        (:meth:`BagWriter.write_ros1`); None for any other topic."""
        for ch in self._layout.channels.values():
            if ch.topic == topic and ch.msgtype in self._layout.ros1_definitions:
                return ch.msgtype, self._layout.ros1_definitions[ch.msgtype]
        return None

    def publishers(self, topic: str) -> frozenset[str]:
        """Who published ``topic`` in this log (its channels' ``usar.publisher``s)."""
        return frozenset(c.publisher for c in self._layout.channels.values() if c.topic == topic)

    def decoded(
        self, topics: Iterable[str], *, only_from: Mapping[str, Collection[str]] | None = None
    ) -> Iterator[tuple[str, msgs.Message | None, int]]:
        """(topic, value, log time) of every message on ``topics``: :meth:`messages` with the
        same checks, order and errors, without a :class:`BagMessage` per message (``usar
        grade`` reads tens of thousands of small messages and needs only these three).

        ``only_from``: topics whose messages count only from these publishers (the rubric's
        trusted detections: the course's detector, never a mission's copy)."""
        only = only_from or {}
        for found in self._chunks(topics, None, None):
            for info, t, data in found:
                allowed = only.get(info.topic)
                if allowed is not None and info.publisher not in allowed:
                    continue
                yield info.topic, _decoded(info.topic, info.msgtype, t, data), t

    def _chunks(
        self, topics: Iterable[str] | None, start_ns: int | None, end_ns: int | None
    ) -> Iterator[list[tuple[mcapfile.ChannelInfo, int, bytes]]]:
        """The wanted messages of each intact chunk that may hold some, a chunk at a time (its
        CRC checked before any of it is given; a damaged one is noted and skipped)."""
        wanted = None if topics is None else set(topics)
        lay = self._layout
        with open(self.path, "rb") as f:
            for ref in list(lay.chunks):
                if ref.problem:
                    continue
                if (start_ns is not None and ref.end_ns < start_ns) or (
                    end_ns is not None and ref.start_ns >= end_ns
                ):
                    continue
                if wanted is not None and not self._may_hold(ref, wanted):
                    continue
                try:
                    found = list(mcapfile.chunk_messages(f, ref, self.size_bytes, lay, wanted))
                except mcapfile.Broken as err:
                    self._note_bad_chunk(ref, str(err))
                    continue
                yield found
                del found

    def _may_hold(self, ref: mcapfile.ChunkRef, wanted: set[str]) -> bool:
        """Whether the chunk may hold a wanted topic (always, when the summary does not say)."""
        if ref.channel_ids is None:
            return True
        chans = self._layout.channels
        return any(chans[c].topic in wanted for c in ref.channel_ids if c in chans)


def _decoded(topic: str, msgtype: str, t: int, data: bytes) -> msgs.Message | None:
    """The value of a logged message; None for a type usar-replay does not know (the bytes are
    kept); :class:`LogError` when the bytes do not decode."""
    try:
        return decode(data, msgtype)
    except KeyError:
        return None
    except Exception as err:
        raise LogError(f"message on {topic} at {t / 1e9:.3f} s cannot be decoded: {err}") from err


# BagMessage is built once per message read: its slots are set directly, which is what its
# frozen __init__ does at about twice the cost (the same object either way).
_new = object.__new__
_set_topic = BagMessage.__dict__["topic"].__set__
_set_msgtype = BagMessage.__dict__["msgtype"].__set__
_set_time = BagMessage.__dict__["log_time_ns"].__set__
_set_data = BagMessage.__dict__["data"].__set__
_set_msg = BagMessage.__dict__["msg"].__set__
_set_publisher = BagMessage.__dict__["publisher"].__set__


def _new_bag_message(
    topic: str, msgtype: str, t: int, data: bytes, msg: msgs.Message | None, publisher: str
) -> BagMessage:
    m: BagMessage = _new(BagMessage)
    _set_topic(m, topic)
    _set_msgtype(m, msgtype)
    _set_time(m, t)
    _set_data(m, data)
    _set_msg(m, msg)
    _set_publisher(m, publisher)
    return m
