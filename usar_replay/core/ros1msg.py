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
parses the definition and deserializes the bytes with rosbags (a fresh typestore per
definition: two packages' ``Header`` never meet).
"""

from __future__ import annotations

import functools
import struct
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from usar_replay.core import msgs

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

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
MAX_DEFINITION_BYTES = 256 * 1024
"""The longest definition accepted (a ``MarkerArray``'s full text is about 5 KiB)."""

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
    if n > MAX_DEFINITION_BYTES or _LEN.size + n > len(data):
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


@functools.lru_cache(maxsize=64)
def _store(msgtype: str, definition: str) -> Typestore:
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.EMPTY)
    store.register(get_types_from_msg(definition, msgtype))
    return store


def decode(msgtype: str, definition: str, data: bytes) -> Any:
    """The message as rosbags' value (a dataclass; arrays of numbers as numpy arrays).
    Raises (rosbags' errors, ``ValueError``) when the definition does not parse or the bytes
    are not a whole message of it."""
    # rosbags refuses bytes left over (a message of another type) as a size mismatch
    return _store(msgtype, definition).deserialize_ros1(bytes(data), ros2_name(msgtype))
