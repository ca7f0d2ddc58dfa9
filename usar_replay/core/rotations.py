"""Planar rotation helpers with names that say their direction (yaw -> quaternion and back).

Why here: the robots of this course move in the plane, so most rotations are a yaw about +z.
These few functions are on hot paths (every odometry message, every controller update), where
scipy's ``Rotation`` costs microseconds per call; for anything more general use
``scipy.spatial.transform.Rotation``. Quaternions are (x, y, z, w), as ROS orders them.
"""

from __future__ import annotations

import math

from usar_replay.core import msgs

__all__ = ["quat_from_yaw", "wrap_angle", "xyzw_from_yaw", "yaw_from_quat", "yaw_from_xyzw"]


def xyzw_from_yaw(yaw: float) -> tuple[float, float, float, float]:
    """The quaternion (x, y, z, w) of a rotation by ``yaw`` radians about +z."""
    return (0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0))


def quat_from_yaw(yaw: float) -> msgs.Quaternion:
    """``geometry_msgs/Quaternion`` of a rotation by ``yaw`` radians about +z."""
    return msgs.Quaternion(z=math.sin(yaw / 2.0), w=math.cos(yaw / 2.0))


def yaw_from_xyzw(x: float, y: float, z: float, w: float) -> float:
    """The heading (rotation about +z, radians in [-pi, pi]) of any quaternion (x, y, z, w)."""
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def yaw_from_quat(q: msgs.Quaternion) -> float:
    """The heading (radians in [-pi, pi]) of a ``geometry_msgs/Quaternion``."""
    return yaw_from_xyzw(q.x, q.y, q.z, q.w)


def wrap_angle(a: float) -> float:
    """``a`` wrapped into [-pi, pi): the difference of two headings, the short way round."""
    return (a + math.pi) % (2.0 * math.pi) - math.pi
