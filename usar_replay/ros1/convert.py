"""usar's message values (ROS 2 types, :mod:`usar_replay.core.msgs`) <-> rospy's ROS 1 messages.

Why generic: the course's ROS 1 types and usar's ROS 2 types have the same fields but for a
few spellings (``builtin_interfaces/Time`` ``sec/nanosec`` vs ROS 1 ``secs/nsecs``, CameraInfo's
``D/K/R/P`` vs ``d/k/r/p``, ROS 1 headers' ``seq``, rosout's level numbers); one walk over
:func:`usar_replay.core.msgs.field_kinds` with those exceptions converts every type the bridge
carries, so a new topic needs no new converter. Runs only in the bridge process (it imports
the ROS 1 message modules by name, from Debian's dist-packages).
"""

from __future__ import annotations

import functools
import importlib
import struct
from typing import Any

from usar_replay.core import msgs

__all__ = ["from_ros1", "log_from_ros1_bytes", "ros1_class", "to_ros1"]

_RENAMED = {("CameraInfo", "d"): "D", ("CameraInfo", "k"): "K", ("CameraInfo", "r"): "R"}
_RENAMED[("CameraInfo", "p")] = "P"

_ROS1_LEVELS = {1: msgs.Log.DEBUG, 2: msgs.Log.INFO, 4: msgs.Log.WARN, 8: msgs.Log.ERROR}
_ROS1_LEVELS[16] = msgs.Log.FATAL


@functools.cache
def ros1_class(msgtype: str) -> Any:
    """``geometry_msgs/msg/Twist`` -> rospy's ``geometry_msgs.msg.Twist`` (looked up once per
    type: the bridge converts some twenty messages a tick)."""
    pkg, _, name = msgtype.split("/")
    return getattr(importlib.import_module(f"{pkg}.msg"), name)


def _time1(t: msgs.Time) -> Any:
    return ros1_time(t.sec, t.nanosec)


def ros1_time(secs: int, nsecs: int) -> Any:
    """rospy's time, made without genpy's checks where the value is already canonical (one
    per header: the bridge makes some twenty a tick, and ``genpy.Time()`` was a tenth of its
    own work); the same value as ``genpy.Time(secs, nsecs)``."""
    import genpy

    if secs >= 0 and 0 <= nsecs < 1_000_000_000:
        out = genpy.Time.__new__(genpy.Time)
        out.secs, out.nsecs = secs, nsecs
        return out
    return genpy.Time(secs, nsecs)


def to_ros1(value: msgs.Message) -> Any:
    """A usar value as the rospy message of the same type (header ``seq`` 0, as tf2 sends)."""
    cls: Any = type(value)
    return _to_ros1_fn(cls)(value)


@functools.cache
def _to_ros1_fn(cls: Any) -> Any:
    """The converter of one type, generated once: one call of the rospy class with every field
    by name (so it makes no default field values to throw away), nested types by their own
    converters."""
    env: dict[str, Any] = {"C": ros1_class(cls.__msgtype__)}
    args = []
    for i, (name, kind, sub) in enumerate(msgs.field_kinds(cls)):
        target = _RENAMED.get((cls.__name__, name), name)
        v = f"o.{name}"
        if kind == "msg":
            env[f"f{i}"] = _time1 if sub is msgs.Time else _to_ros1_fn(sub)
            conv = f"f{i}({v})"
        elif kind == "msgs":
            env[f"f{i}"] = _to_ros1_fn(sub)
            conv = f"[f{i}(x) for x in {v}]"
        elif kind == "bytes" and cls is msgs.OccupancyGrid:
            conv = f"[b - 256 if b > 127 else b for b in {v}]"  # int8[]
        elif kind in ("floats", "ints"):
            conv = f"list({v})"
        else:
            conv = v
        args.append(f"{target}={conv}")
    code = f"def conv(o):\n    return C({', '.join(args)})\n"
    exec(code, env)
    return env["conv"]


def from_ros1(cls: type[msgs.Message], value: Any) -> msgs.Message:
    """A rospy message as usar's value of type ``cls`` (fields the ROS 2 type lacks, such as
    a header's ``seq``, are dropped)."""
    if cls is msgs.Time:
        return msgs.Time(sec=int(value.secs), nanosec=int(value.nsecs))
    kwargs: dict[str, Any] = {}
    for name, kind, sub in msgs.field_kinds(cls):
        v = getattr(value, _RENAMED.get((cls.__name__, name), name))
        if kind == "msg":
            kwargs[name] = from_ros1(sub, v)
        elif kind == "msgs":
            kwargs[name] = tuple(from_ros1(sub, x) for x in v)
        elif kind == "bytes":
            kwargs[name] = bytes(b & 0xFF for b in v) if not isinstance(v, bytes) else v
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


_HEADER = struct.Struct("<3I")
_U32 = struct.Struct("<I")
_LEVEL = struct.Struct("<b")
_LINE_TOPICS = struct.Struct("<2I")


def log_from_ros1_bytes(data: bytes) -> msgs.Log | None:
    """A serialized ``rosgraph_msgs/Log`` (ROS 1 levels 1/2/4/8/16) as ``rcl_interfaces/Log``
    (10/20/30/40/50), without rospy's message object in between (None where rospy's would not
    deserialize: a truncated message). Why: a package that logs in a busy loop sends a few
    lines a tick, and rospy's ``deserialize`` and the conversion after it, on the bridge's
    receiving thread, were part of every such tick's wait. Strings as genpy decodes them
    (UTF-8, a bad byte replaced)."""
    try:
        _seq, secs, nsecs = _HEADER.unpack_from(data, 0)
        _frame_id, at = _text(data, _HEADER.size)
        (level,) = _LEVEL.unpack_from(data, at)
        name, at = _text(data, at + 1)
        text, at = _text(data, at)
        file, at = _text(data, at)
        function, at = _text(data, at)
        (line, count) = _LINE_TOPICS.unpack_from(data, at)  # topics[]: read as rospy's, not kept
        at += _LINE_TOPICS.size
        for _ in range(count):  # as genpy: a length must be there, its string may run short
            (n,) = _U32.unpack_from(data, at)
            at += 4 + n
    except struct.error:
        return None
    return msgs.Log(
        stamp=msgs.Time(sec=secs, nanosec=nsecs),
        level=_ROS1_LEVELS.get(level, msgs.Log.INFO),
        name=name.lstrip("/"),
        msg=text,
        file=file,
        function=function,
        line=line,
    )


def _text(data: bytes, at: int) -> tuple[str, int]:
    """The ROS 1 string at ``at`` (a length, then UTF-8) and where the next field starts;
    struct.error where it runs past the end (genpy then fails at the field after it)."""
    (n,) = _U32.unpack_from(data, at)
    at += 4
    if at + n > len(data):
        raise struct.error("a string past the message's end")
    return data[at : at + n].decode("utf-8", "replace"), at + n
