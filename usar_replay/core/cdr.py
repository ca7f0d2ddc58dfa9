"""CDR: ROS 2 messages <-> the bytes written to the log and sent to a mission process.

Why its own module: the log (``bag``), the mission process boundary (``worker``) and the tests
all need the same bytes for the same message, and the mission process must not import the log's
storage library. Serialisation is rosbags' (a well-kept implementation of ROS 2's CDR); this
module only converts :mod:`usar_replay.core.msgs` values to and from rosbags' typestore objects.

Decoding, the hot path of ``usar grade`` and replay, first tries the generated decoders of
:mod:`usar_replay.core.cdrdecode` (bytes straight to our values, same results, several times faster)
and uses rosbags for whatever they leave (:func:`decode_reference` is rosbags alone). rosbags
and numpy are imported on first use, so a process that only decodes never loads them.
"""

from __future__ import annotations

import functools
from typing import TYPE_CHECKING, Any

from usar_replay.core import cdrdecode, msgs

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

__all__ = ["decode", "decode_reference", "encode", "schema_text", "typestore"]


@functools.cache
def typestore() -> Typestore:
    """A rosbags typestore holding exactly the definitions declared in
    :mod:`usar_replay.core.msgs`."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.EMPTY)
    for cls in msgs.MESSAGE_TYPES:
        store.register(get_types_from_msg(cls.__msgdef__, cls.__msgtype__))
    return store


@functools.cache
def schema_text(msgtype: str) -> str:
    """The ``ros2msg`` schema of a type: its definition followed by every dependency's."""
    text, _ = typestore().generate_msgdef(msgtype, ros_version=2)
    return text


# Converters between our values and rosbags' objects, generated once per class as plain Python
# (one keyword call per message, no per-field dispatch): decoding a log is mostly this work.

_Conv = Any


@functools.cache
def _to_ros_fn(cls: Any) -> _Conv:
    import numpy as np

    store = typestore()
    env: dict[str, Any] = {"T": store.types[cls.__msgtype__], "np": np, "u8": np.uint8}
    args = []
    for i, (name, kind, elem) in enumerate(msgs.field_kinds(cls)):
        v = f"v.{name}"
        if kind == "msg":
            env[f"c{i}"] = _to_ros_fn(elem)
            args.append(f"{name}=c{i}({v})")
        elif kind == "msgs":
            env[f"c{i}"] = _to_ros_fn(elem)
            args.append(f"{name}=[c{i}(x) for x in {v}]")
        elif kind == "bytes":
            args.append(f"{name}=np.frombuffer({v}, dtype=u8)")
        elif kind == "floats":
            args.append(f"{name}=np.asarray({v}, dtype=np.float64)")
        elif kind == "ints":
            args.append(f"{name}=np.asarray({v}, dtype=np.int64)")
        else:
            args.append(f"{name}={v}")
    code = f"def conv(v):\n    return T({', '.join(args)})\n"
    exec(code, env)
    return env["conv"]


@functools.cache
def _from_ros_fn(cls: Any) -> _Conv:
    env: dict[str, Any] = {"C": cls, "tuple": tuple, "float": float, "int": int}
    args = []
    for i, (name, kind, elem) in enumerate(msgs.field_kinds(cls)):
        v = f"o.{name}"
        if kind == "msg":
            env[f"c{i}"] = _from_ros_fn(elem)
            args.append(f"{name}=c{i}({v})")
        elif kind == "msgs":
            env[f"c{i}"] = _from_ros_fn(elem)
            args.append(f"{name}=tuple([c{i}(x) for x in {v}])")
        elif kind == "bytes":
            args.append(f"{name}=bytes({v})")
        elif kind == "floats":
            args.append(f"{name}=tuple([float(x) for x in {v}])")
        elif kind == "ints":
            args.append(f"{name}=tuple([int(x) for x in {v}])")
        else:
            args.append(
                f"{name}={dict(float='float', int='int', bool='bool', str='str')[kind]}({v})"
            )
    code = f"def conv(o):\n    return C({', '.join(args)})\n"
    exec(code, env)
    return env["conv"]


def _to_ros(value: msgs.Message, store: Typestore) -> Any:
    cls: Any = type(value)
    return _to_ros_fn(cls)(value)


def _from_ros(obj: Any, cls: type[msgs.Message]) -> msgs.Message:
    key: Any = cls
    result: msgs.Message = _from_ros_fn(key)(obj)
    return result


def encode(msg: msgs.Message) -> bytes:
    """CDR bytes of a message, exactly as they are written to the log."""
    store = typestore()
    return bytes(store.serialize_cdr(_to_ros(msg, store), type(msg).__msgtype__))


_FAST: dict[str, cdrdecode.Decoder | None] = {}
"""The generated decoder of each type name met so far (None: that type goes to rosbags)."""


def decode(data: bytes, msgtype: str) -> msgs.Message:
    """The typed message of CDR ``data`` of ROS 2 type ``msgtype`` (``pkg/msg/Type``).

    The generated decoder when it takes the bytes, else rosbags: the same value either way,
    and rosbags' error for bytes that do not decode. KeyError for a type usar-replay lacks."""
    try:
        fast = _FAST[msgtype]
    except KeyError:
        fast = _FAST[msgtype] = cdrdecode.decoder(msgs.message_class(msgtype))
    if fast is not None:
        if type(data) is not bytes:  # its slices must be bytes, as the fields are
            data = bytes(data)
        try:
            return fast(data)
        except Exception:  # noqa: BLE001 - rosbags decides: its value, or its error
            pass
    return decode_reference(data, msgtype)


def decode_reference(data: bytes, msgtype: str) -> msgs.Message:
    """:func:`decode` by rosbags alone (the reference the generated decoders are tested
    against)."""
    cls = msgs.message_class(msgtype)
    return _from_ros(typestore().deserialize_cdr(data, msgtype), cls)
