"""CDR: ROS 2 messages <-> the bytes written to the log and sent to a mission process.

Why its own module: the log (``bag``), the mission process boundary (``worker``) and the tests
all need the same bytes for the same message, and the mission process must not import the log's
storage library. Serialisation is rosbags' (a well-kept implementation of ROS 2's CDR); this
module only converts :mod:`usar_replay.msgs` values to and from rosbags' typestore objects.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore

from usar_replay import msgs

__all__ = ["decode", "encode", "schema_text", "typestore"]


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
        elif kind == "ints":
            kwargs[name] = np.asarray(v, dtype=np.int64)
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
        elif kind == "ints":
            kwargs[name] = tuple(int(x) for x in v)
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
