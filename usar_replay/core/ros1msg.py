"""ROS 1 messages usar has no ROS 2 value for: kept as their own bytes, read with rosbags.

Why: a ROS 1 package publishes on topics of its own (a ``std_msgs/Int32`` counter, a
``visualization_msgs/MarkerArray``, a message type of its own package) that
:mod:`usar_replay.core.msgs` does not declare. ``rosbag record -a`` keeps them, so usar keeps
them too, in MCAP's ``ros1`` message encoding with a ``ros1msg`` schema (the type's full
definition, as rospy gives it: the connection header's ``message_definition``), which Foxglove
and rosbags read. Nothing is converted: the bytes in the log are the bytes on the wire.

:class:`Ros1Message` carries one such message across the bridge's socket and the recorder's
checks (``msgtype`` ``pkg/Type``, ``definition``, ``data``); :func:`pack`/:func:`unpack` are
its wire form (the tick protocol's ``ros1:pkg/Type`` type name marks it); :func:`decode`
deserializes the bytes with rosbags, through :mod:`usar_replay.core.ros1defs` (the definition's
shape capped before it is parsed, a fresh typestore per definition: two packages' ``Header``
never meet).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from typing import Any

from usar_replay.core import msgs
from usar_replay.core.ros1defs import DefinitionLimits, Definitions

__all__ = [
    "MESSAGE_ENCODING",
    "SCHEMA_ENCODING",
    "WIRE_PREFIX",
    "Ros1Message",
    "decode",
    "pack",
    "ros2_name",
    "unpack",
]

WIRE_PREFIX = "ros1:"
"""The tick protocol's type name of a ROS 1 message: ``ros1:std_msgs/Int32``."""
MESSAGE_ENCODING = "ros1"
SCHEMA_ENCODING = "ros1msg"
MAX_DEFINITION_BYTES = DefinitionLimits().max_bytes
"""The longest definition accepted on the wire (64 KiB; a ``MarkerArray``'s full text is about
5 KiB); :mod:`usar_replay.core.ros1defs` caps the rest of its shape."""

_LEN = struct.Struct("<I")


@dataclass(frozen=True, slots=True, kw_only=True)
class Ros1Message(msgs.Message):
    """One ROS 1 message as it was on the wire (not a type of :data:`msgs.MESSAGE_TYPES`)."""

    msgtype: str = ""
    """The ROS 1 type name, ``pkg/Type``."""
    definition: str = ""
    """The type's full definition (``MSG: pkg/Dep`` sections for its dependencies)."""
    data: bytes = b""
    """The ROS 1 serialisation."""


def pack(message: Ros1Message) -> tuple[str, bytes]:
    """(wire type name, wire bytes) of ``message``: the definition then the data."""
    definition = message.definition.encode()
    return WIRE_PREFIX + message.msgtype, _LEN.pack(len(definition)) + definition + message.data


def unpack(wire_type: str, data: bytes) -> Ros1Message:
    """The message :func:`pack` made; ``ValueError`` for anything else."""
    if not wire_type.startswith(WIRE_PREFIX):
        raise ValueError(f"{wire_type!r} is not a ROS 1 wire type")
    if len(data) < _LEN.size:
        raise ValueError("a ROS 1 message shorter than its header")
    (n,) = _LEN.unpack_from(data)
    if n > MAX_DEFINITION_BYTES:
        raise ValueError(
            f"a ROS 1 definition of {n:,} bytes; a definition is at most {MAX_DEFINITION_BYTES:,}"
        )
    if _LEN.size + n > len(data):
        raise ValueError(f"a ROS 1 definition of {n} bytes")
    end = _LEN.size + n
    return Ros1Message(
        msgtype=wire_type.removeprefix(WIRE_PREFIX),
        definition=data[_LEN.size : end].decode(),
        data=bytes(data[end:]),
    )


def ros2_name(msgtype: str) -> str:
    """``std_msgs/Int32`` -> ``std_msgs/msg/Int32`` (rosbags' and usar's spelling)."""
    pkg, _, name = msgtype.partition("/")
    return msgtype if "/msg/" in msgtype else f"{pkg}/msg/{name}"


def decode(
    msgtype: str, definition: str, data: bytes, definitions: Definitions | None = None
) -> Any:
    """The message as rosbags' value (a dataclass; arrays of numbers as numpy arrays).
    Raises (:class:`~usar_replay.core.ros1defs.DefinitionRefused`, rosbags' errors,
    ``ValueError``) when the definition is past a cap, does not parse, or the bytes are not a
    whole message of it. ``definitions``: the run's (or the log read's) parsed definitions and
    budgets; without it, a fresh set for this one message."""
    return (definitions or Definitions()).decode(msgtype, definition, data)
