"""The mission wire protocol: the frames usar and a mission process exchange on their socket.

Why a module of its own: three programs speak it (the recorder's side,
:class:`usar_replay.process.mission_process.MissionProcess`; the Python mission process,
:mod:`usar_replay.process.worker`; and the ROS 1 bridge, :mod:`usar_replay.ros1.bridge`), and the
bytes must mean the same to all three. Nothing from the mission process is ever unpickled: the
parent parses these frames itself (only the parent -> child setup, sent first, is a pickle, which
is safe in that direction).

Each frame is one ``multiprocessing.connection`` message (a 4-byte big-endian length, then the
payload; :mod:`usar_replay.process.wire_io` writes it with a deadline). The payload's first byte is
its :class:`FrameKind`:

* ``T`` (tick, parent -> child) and ``O`` (outputs, child -> parent) carry messages::

      kind    1 byte
      t_ns    int64, little-endian    the tick's sim time
      count   uint32, little-endian   the number of items
      flag    1 byte                  outputs: bit 0 the mission said it is done; the
                                      ROS 1 bridge's pacing: bit 1 the tick held for a
                                      shutdown, bit 2 its wall cap ran out
      count items, each:
        topic_len uint16 LE, type_len uint16 LE, data_len uint32 LE,
        topic (UTF-8), type (UTF-8, a ROS 2 type name), data (CDR)

  nothing may follow the last item.
* ``R`` (ready, child -> parent, once the mission's ``main()`` created its nodes): the kind and
  :data:`PROTOCOL_VERSION` as a uint16 LE. A parent that reads another version ends the run
  as ``refused`` (:class:`~usar_replay.core.errors.ProtocolMismatch`, which says so); a child
  given a setup of another version loads no mission code and answers with its own ready.
* ``C`` (crashed), ``M`` (out of memory), ``F`` (refused): the kind and the user's traceback or
  the reason as UTF-8 text; the child sends one and ends.
* ``S`` (stop, parent -> child): the kind alone.

The wire is not recorded: a log holds the messages, never these frames.
"""

from __future__ import annotations

import struct
from collections.abc import Sequence
from enum import Enum
from typing import NamedTuple

from usar_replay.core.errors import ProtocolMismatch

__all__ = [
    "FLAG_CAPPED",
    "FLAG_DONE",
    "FLAG_HELD",
    "PROTOCOL_VERSION",
    "Frame",
    "FrameKind",
    "Wire",
    "check_ready",
    "outputs_frame",
    "pack",
    "ready_frame",
    "text_frame",
    "text_of",
    "tick_frame",
    "unpack",
]

PROTOCOL_VERSION = 1
"""Bumped whenever a frame's layout or meaning changes."""

Wire = tuple[str, str, bytes]
"""One message on the wire: (topic, ROS 2 type name, CDR bytes)."""


class FrameKind(bytes, Enum):
    """A frame's first byte (each member *is* that one byte: ``FrameKind.STOP == b"S"``)."""

    TICK = b"T"
    OUTPUTS = b"O"
    READY = b"R"
    STOP = b"S"
    CRASHED = b"C"
    OUT_OF_MEMORY = b"M"
    REFUSED = b"F"


MESSAGE_KINDS = (FrameKind.TICK, FrameKind.OUTPUTS)
"""The kinds whose payload is :func:`pack`'s layout."""

_HDR = struct.Struct("<qI")
_ITEM = struct.Struct("<HHI")
_VERSION = struct.Struct("<H")


class Frame(NamedTuple):
    """A message frame read back by :func:`unpack`."""

    kind: bytes
    t_ns: int
    items: list[Wire]
    flag: int


def pack(kind: bytes, t_ns: int, items: Sequence[Wire], flag: int = 0) -> bytes:
    """A tick or outputs frame (the layout in the module doc)."""
    parts = [bytes(kind), _HDR.pack(t_ns, len(items)), bytes([flag])]
    for topic, msgtype, data in items:
        tb, mb = topic.encode(), msgtype.encode()
        parts += [_ITEM.pack(len(tb), len(mb), len(data)), tb, mb, data]
    return b"".join(parts)


def tick_frame(t_ns: int, inputs: Sequence[Wire]) -> bytes:
    """The parent's tick: its sim time and the messages the mission may subscribe to."""
    return pack(FrameKind.TICK, t_ns, inputs)


FLAG_DONE = 1
"""Outputs flag: the mission said it is done."""
FLAG_HELD = 2
"""Outputs flag: the ROS 1 bridge held the tick for a node's shutdown (counted, budgeted)."""
FLAG_CAPPED = 4
"""Outputs flag: the tick's wall cap ran out before the ROS 1 graph went idle."""
FLAG_DETECTIONS_READ = 8
"""Outputs flag: a node of the ROS 1 graph subscribes to ``/fiducial_transforms`` (the
master says so; the rubric counts a detection only for a package that could use it)."""


def outputs_frame(t_ns: int, outputs: Sequence[Wire], done: bool | int = False) -> bytes:
    """The child's answer to a tick: what the mission published, and whether it is done
    (with the pacing flags: :data:`FLAG_HELD`, :data:`FLAG_CAPPED`)."""
    return pack(FrameKind.OUTPUTS, t_ns, outputs, int(done))


def unpack(frame: bytes) -> Frame:
    """Read a frame :func:`pack` wrote; a :class:`ValueError` (one line) says what is wrong with
    any other bytes (cut short, a count past its end, bytes after the last item, text that is
    not UTF-8). The kind is not checked: the caller knows which it expects."""
    try:
        kind = frame[:1]
        t_ns, n = _HDR.unpack_from(frame, 1)
        pos = 1 + _HDR.size
        flag = frame[pos]
        pos += 1
        items: list[Wire] = []
        for _ in range(n):
            lt, lm, ld = _ITEM.unpack_from(frame, pos)
            pos += _ITEM.size
            end = pos + lt + lm + ld
            if end > len(frame):
                raise ValueError(f"item {len(items)} runs {end - len(frame)} bytes past the end")
            topic = frame[pos : pos + lt].decode()
            pos += lt
            msgtype = frame[pos : pos + lm].decode()
            pos += lm
            items.append((topic, msgtype, frame[pos : pos + ld]))
            pos += ld
    except (IndexError, struct.error) as err:
        raise ValueError(f"a frame of {len(frame)} bytes is cut short ({err})") from None
    except UnicodeDecodeError:
        raise ValueError(f"item {len(items)}'s topic or type is not UTF-8") from None
    if pos != len(frame):
        raise ValueError(f"{len(frame) - pos} bytes after the last item of the frame")
    return Frame(kind, t_ns, items, flag)


def text_frame(kind: FrameKind, text: str) -> bytes:
    """A crashed, out-of-memory or refused frame: the kind, then ``text`` as UTF-8."""
    return kind + text.encode("utf-8", errors="replace")


def text_of(frame: bytes) -> str:
    """The text of a :func:`text_frame` (bytes that are not UTF-8 shown as U+FFFD)."""
    return frame[1:].decode("utf-8", errors="replace")


_INFO = b"I"
"""Between a ready frame's version and its ``info``."""


def ready_frame(info: str = "") -> bytes:
    """What a mission process sends once it is ready: ``R``, its protocol version and
    ``info`` (UTF-8; the ROS 1 bridge's facts of the run as it configured it, '' for a
    mission process): a channel the run's other processes cannot write, unlike its folder."""
    head = FrameKind.READY + _VERSION.pack(PROTOCOL_VERSION)
    return head + _INFO + info.encode("utf-8") if info else head


def check_ready(frame: bytes, peer: str = "the mission process") -> str:
    """The ``info`` of a :func:`ready_frame` of this version; raise :class:`ProtocolMismatch`
    for another version (a frame of another kind is the caller's to judge first)."""
    head = ready_frame()
    if frame == head:
        return ""
    if frame[: len(head) + 1] == head + _INFO:
        return frame[len(head) + 1 :].decode("utf-8", errors="replace")
    theirs = (
        f"protocol version {_VERSION.unpack(frame[1:])[0]}"
        if len(frame) == 1 + _VERSION.size
        else "no protocol version usar knows"
    )
    raise ProtocolMismatch(
        f"{peer} speaks {theirs}, this usar speaks version {PROTOCOL_VERSION}: both must come "
        "from one installation of usar-replay (reinstall it), and mission code must not write "
        "to usar's socket"
    )
