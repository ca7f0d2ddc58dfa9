"""Everything a mission imports: ``from usar_replay.api import Node, Twist, ...``.

Why one module: a student's mission should need one import line, in the spirit of ``rclpy`` +
``tf2_ros`` + the message packages, and usar should be free to move things between its own
modules without breaking anyone's mission. What is here is the public, documented node API
(``docs/node-api.md``); everything else in the package is usar's own business.
"""

from __future__ import annotations

from usar_replay.core import contract
from usar_replay.core.msgs import (
    ArucoMarkers,
    Bool,
    CameraInfo,
    CompressedImage,
    DiagnosticStatus,
    FiducialTransform,
    FiducialTransformArray,
    Header,
    KeyValue,
    Log,
    MapMetaData,
    OccupancyGrid,
    Odometry,
    Path,
    Point,
    Pose,
    PoseStamped,
    Quaternion,
    String,
    TFMessage,
    Transform,
    TransformStamped,
    Twist,
    Vector3,
)
from usar_replay.core.rotations import quat_from_yaw, wrap_angle, yaw_from_quat
from usar_replay.node.executor import shutdown
from usar_replay.node.navigation import NavigateClient, NavResult
from usar_replay.node.node import Duration, Node, Parameter, ParameterNotDeclared, Time, Timer
from usar_replay.node.tf2 import (
    Buffer,
    ConnectivityException,
    ExtrapolationException,
    LookupException,
    StaticTransformBroadcaster,
    TransformBroadcaster,
    TransformException,
    TransformListener,
)
from usar_replay.world.nav import PlanningGrid, grid_from_msg

__all__ = [
    "ArucoMarkers",
    "Bool",
    "Buffer",
    "CameraInfo",
    "CompressedImage",
    "ConnectivityException",
    "DiagnosticStatus",
    "Duration",
    "ExtrapolationException",
    "FiducialTransform",
    "FiducialTransformArray",
    "Header",
    "KeyValue",
    "Log",
    "LookupException",
    "MapMetaData",
    "NavResult",
    "NavigateClient",
    "Node",
    "OccupancyGrid",
    "Odometry",
    "Parameter",
    "ParameterNotDeclared",
    "Path",
    "Point",
    "Pose",
    "PlanningGrid",
    "PoseStamped",
    "Quaternion",
    "StaticTransformBroadcaster",
    "String",
    "TFMessage",
    "Time",
    "Timer",
    "Transform",
    "TransformBroadcaster",
    "TransformException",
    "TransformListener",
    "TransformStamped",
    "Twist",
    "Vector3",
    "contract",
    "grid_from_msg",
    "quat_from_yaw",
    "shutdown",
    "wrap_angle",
    "yaw_from_quat",
]
