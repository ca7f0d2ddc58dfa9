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
from typing import Any

from usar_replay.core import msgs

__all__ = ["from_ros1", "log_from_ros1", "ros1_class", "to_ros1"]

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
    import genpy

    return genpy.Time(t.sec, t.nanosec)


def to_ros1(value: msgs.Message) -> Any:
    """A usar value as the rospy message of the same type (header ``seq`` 0, as tf2 sends)."""
    cls = type(value)
    out = ros1_class(cls.__msgtype__)()
    for name, kind, sub in msgs.field_kinds(cls):
        v = getattr(value, name)
        if kind == "msg":
            conv = _time1(v) if sub is msgs.Time else to_ros1(v)
        elif kind == "msgs":
            conv = [to_ros1(x) for x in v]
        elif kind == "bytes" and cls is msgs.OccupancyGrid:
            conv = [b - 256 if b > 127 else b for b in v]  # int8[]
        elif kind in ("floats", "ints"):
            conv = list(v)
        else:
            conv = v
        setattr(out, _RENAMED.get((cls.__name__, name), name), conv)
    return out


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


def log_from_ros1(value: Any) -> msgs.Log:
    """rosgraph_msgs/Log (ROS 1 levels 1/2/4/8/16) as rcl_interfaces/Log (10/20/30/40/50)."""
    return msgs.Log(
        stamp=msgs.Time(sec=int(value.header.stamp.secs), nanosec=int(value.header.stamp.nsecs)),
        level=_ROS1_LEVELS.get(int(value.level), msgs.Log.INFO),
        name=str(value.name).lstrip("/"),
        msg=str(value.msg),
        file=str(value.file),
        function=str(value.function),
        line=int(value.line),
    )
