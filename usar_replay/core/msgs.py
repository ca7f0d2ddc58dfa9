"""ROS 2 messages as typed, immutable Python values.

Why our own classes rather than rosbags' generated ones: the mission, the replay and the tests
build and compare messages all the time, so they need keyword construction with ROS 2's default
values, value equality (``==`` on two messages compares every field, including image bytes), and
types a checker can follow. Serialisation is not ours: :mod:`usar_replay.log.bag` converts these
values to rosbags' typestore objects and lets rosbags write the CDR bytes.

Each class carries its ROS 2 name (``__msgtype__``, always ``pkg/msg/Type``) and the text of its
``.msg`` definition (``__msgdef__``); :func:`typestore` registers exactly these texts, so the
schemas written to the log are the ones declared here.

Field conventions: ``float64``/``float32`` -> ``float``; integer types -> ``int``; ``string`` ->
``str``; ``uint8[]`` -> ``bytes``; other numeric arrays -> ``tuple[float, ...]``; message arrays
-> ``tuple[Msg, ...]``. Stamps are :class:`Time`; :meth:`Time.from_ns` and :attr:`Time.ns` convert
to the integer nanoseconds used everywhere else in usar-replay.
"""

from __future__ import annotations

import dataclasses
import functools
import typing
from dataclasses import dataclass, field
from typing import Any, ClassVar, cast

__all__ = [
    "Message",
    "Time",
    "Duration",
    "Header",
    "String",
    "Bool",
    "Vector3",
    "Quaternion",
    "Point",
    "Pose",
    "PoseStamped",
    "PoseArray",
    "PoseWithCovariance",
    "PoseWithCovarianceStamped",
    "Transform",
    "TransformStamped",
    "Twist",
    "TwistWithCovariance",
    "TFMessage",
    "RegionOfInterest",
    "CompressedImage",
    "CameraInfo",
    "Odometry",
    "Path",
    "Log",
    "FiducialTransform",
    "FiducialTransformArray",
    "ArucoMarkers",
    "KeyValue",
    "DiagnosticStatus",
    "MapMetaData",
    "OccupancyGrid",
    "MESSAGE_TYPES",
    "message_class",
]

NS_PER_S = 1_000_000_000


@dataclass(frozen=True, slots=True, kw_only=True)
class Message:
    """Base of every message value: a frozen dataclass with its ROS 2 type name and definition."""

    __msgtype__: ClassVar[str] = ""
    __msgdef__: ClassVar[str] = ""


@dataclass(frozen=True, slots=True, kw_only=True)
class Time(Message):
    """builtin_interfaces/msg/Time. Sim time; ``sec`` and ``nanosec`` as ROS 2 splits them."""

    __msgtype__: ClassVar[str] = "builtin_interfaces/msg/Time"
    __msgdef__: ClassVar[str] = "int32 sec\nuint32 nanosec\n"
    sec: int = 0
    nanosec: int = 0

    @classmethod
    def from_ns(cls, ns: int) -> Time:
        """Split integer nanoseconds into (sec, nanosec) the way rclpy does (nanosec < 1e9)."""
        sec, nanosec = divmod(int(ns), NS_PER_S)
        return cls(sec=sec, nanosec=nanosec)

    @property
    def ns(self) -> int:
        """The stamp as integer nanoseconds, the unit of MCAP log times."""
        return self.sec * NS_PER_S + self.nanosec


@dataclass(frozen=True, slots=True, kw_only=True)
class Duration(Message):
    """builtin_interfaces/msg/Duration."""

    __msgtype__: ClassVar[str] = "builtin_interfaces/msg/Duration"
    __msgdef__: ClassVar[str] = "int32 sec\nuint32 nanosec\n"
    sec: int = 0
    nanosec: int = 0


@dataclass(frozen=True, slots=True, kw_only=True)
class Header(Message):
    """std_msgs/msg/Header."""

    __msgtype__: ClassVar[str] = "std_msgs/msg/Header"
    __msgdef__: ClassVar[str] = "builtin_interfaces/Time stamp\nstring frame_id\n"
    stamp: Time = field(default_factory=Time)
    frame_id: str = ""


@dataclass(frozen=True, slots=True, kw_only=True)
class String(Message):
    """std_msgs/msg/String."""

    __msgtype__: ClassVar[str] = "std_msgs/msg/String"
    __msgdef__: ClassVar[str] = "string data\n"
    data: str = ""


@dataclass(frozen=True, slots=True, kw_only=True)
class Bool(Message):
    """std_msgs/msg/Bool (the built-in mission switches its detector on and off with one)."""

    __msgtype__: ClassVar[str] = "std_msgs/msg/Bool"
    __msgdef__: ClassVar[str] = "bool data\n"
    data: bool = False


@dataclass(frozen=True, slots=True, kw_only=True)
class Vector3(Message):
    """geometry_msgs/msg/Vector3."""

    __msgtype__: ClassVar[str] = "geometry_msgs/msg/Vector3"
    __msgdef__: ClassVar[str] = "float64 x\nfloat64 y\nfloat64 z\n"
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0


@dataclass(frozen=True, slots=True, kw_only=True)
class Quaternion(Message):
    """geometry_msgs/msg/Quaternion; the ROS 2 default is the identity (w = 1)."""

    __msgtype__: ClassVar[str] = "geometry_msgs/msg/Quaternion"
    __msgdef__: ClassVar[str] = "float64 x\nfloat64 y\nfloat64 z\nfloat64 w\n"
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    w: float = 1.0


@dataclass(frozen=True, slots=True, kw_only=True)
class Point(Message):
    """geometry_msgs/msg/Point."""

    __msgtype__: ClassVar[str] = "geometry_msgs/msg/Point"
    __msgdef__: ClassVar[str] = "float64 x\nfloat64 y\nfloat64 z\n"
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0


@dataclass(frozen=True, slots=True, kw_only=True)
class Pose(Message):
    """geometry_msgs/msg/Pose."""

    __msgtype__: ClassVar[str] = "geometry_msgs/msg/Pose"
    __msgdef__: ClassVar[str] = (
        "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n"
    )
    position: Point = field(default_factory=Point)
    orientation: Quaternion = field(default_factory=Quaternion)


@dataclass(frozen=True, slots=True, kw_only=True)
class PoseStamped(Message):
    """geometry_msgs/msg/PoseStamped."""

    __msgtype__: ClassVar[str] = "geometry_msgs/msg/PoseStamped"
    __msgdef__: ClassVar[str] = "std_msgs/Header header\ngeometry_msgs/Pose pose\n"
    header: Header = field(default_factory=Header)
    pose: Pose = field(default_factory=Pose)


@dataclass(frozen=True, slots=True, kw_only=True)
class PoseArray(Message):
    """geometry_msgs/msg/PoseArray."""

    __msgtype__: ClassVar[str] = "geometry_msgs/msg/PoseArray"
    __msgdef__: ClassVar[str] = "std_msgs/Header header\ngeometry_msgs/Pose[] poses\n"
    header: Header = field(default_factory=Header)
    poses: tuple[Pose, ...] = ()


@dataclass(frozen=True, slots=True, kw_only=True)
class PoseWithCovariance(Message):
    """geometry_msgs/msg/PoseWithCovariance (row-major 6x6 covariance)."""

    __msgtype__: ClassVar[str] = "geometry_msgs/msg/PoseWithCovariance"
    __msgdef__: ClassVar[str] = "geometry_msgs/Pose pose\nfloat64[36] covariance\n"
    pose: Pose = field(default_factory=Pose)
    covariance: tuple[float, ...] = (0.0,) * 36


@dataclass(frozen=True, slots=True, kw_only=True)
class PoseWithCovarianceStamped(Message):
    """geometry_msgs/msg/PoseWithCovarianceStamped (amcl's ``amcl_pose``)."""

    __msgtype__: ClassVar[str] = "geometry_msgs/msg/PoseWithCovarianceStamped"
    __msgdef__: ClassVar[str] = "std_msgs/Header header\ngeometry_msgs/PoseWithCovariance pose\n"
    header: Header = field(default_factory=Header)
    pose: PoseWithCovariance = field(default_factory=PoseWithCovariance)


@dataclass(frozen=True, slots=True, kw_only=True)
class Transform(Message):
    """geometry_msgs/msg/Transform."""

    __msgtype__: ClassVar[str] = "geometry_msgs/msg/Transform"
    __msgdef__: ClassVar[str] = (
        "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation\n"
    )
    translation: Vector3 = field(default_factory=Vector3)
    rotation: Quaternion = field(default_factory=Quaternion)


@dataclass(frozen=True, slots=True, kw_only=True)
class TransformStamped(Message):
    """geometry_msgs/msg/TransformStamped: the pose of ``child_frame_id`` in ``header.frame_id``."""

    __msgtype__: ClassVar[str] = "geometry_msgs/msg/TransformStamped"
    __msgdef__: ClassVar[str] = (
        "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform\n"
    )
    header: Header = field(default_factory=Header)
    child_frame_id: str = ""
    transform: Transform = field(default_factory=Transform)


@dataclass(frozen=True, slots=True, kw_only=True)
class Twist(Message):
    """geometry_msgs/msg/Twist (cmd_vel): linear m/s and angular rad/s in the robot's base frame."""

    __msgtype__: ClassVar[str] = "geometry_msgs/msg/Twist"
    __msgdef__: ClassVar[str] = "geometry_msgs/Vector3 linear\ngeometry_msgs/Vector3 angular\n"
    linear: Vector3 = field(default_factory=Vector3)
    angular: Vector3 = field(default_factory=Vector3)


@dataclass(frozen=True, slots=True, kw_only=True)
class TwistWithCovariance(Message):
    """geometry_msgs/msg/TwistWithCovariance."""

    __msgtype__: ClassVar[str] = "geometry_msgs/msg/TwistWithCovariance"
    __msgdef__: ClassVar[str] = "geometry_msgs/Twist twist\nfloat64[36] covariance\n"
    twist: Twist = field(default_factory=Twist)
    covariance: tuple[float, ...] = (0.0,) * 36


@dataclass(frozen=True, slots=True, kw_only=True)
class TFMessage(Message):
    """tf2_msgs/msg/TFMessage, the type of ``/tf`` and ``/tf_static``."""

    __msgtype__: ClassVar[str] = "tf2_msgs/msg/TFMessage"
    __msgdef__: ClassVar[str] = "geometry_msgs/TransformStamped[] transforms\n"
    transforms: tuple[TransformStamped, ...] = ()


@dataclass(frozen=True, slots=True, kw_only=True)
class RegionOfInterest(Message):
    """sensor_msgs/msg/RegionOfInterest."""

    __msgtype__: ClassVar[str] = "sensor_msgs/msg/RegionOfInterest"
    __msgdef__: ClassVar[str] = (
        "uint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool do_rectify\n"
    )
    x_offset: int = 0
    y_offset: int = 0
    height: int = 0
    width: int = 0
    do_rectify: bool = False


@dataclass(frozen=True, slots=True, kw_only=True)
class CompressedImage(Message):
    """sensor_msgs/msg/CompressedImage; ``format`` is "png" or "jpeg", ``data`` the file bytes."""

    __msgtype__: ClassVar[str] = "sensor_msgs/msg/CompressedImage"
    __msgdef__: ClassVar[str] = "std_msgs/Header header\nstring format\nuint8[] data\n"
    header: Header = field(default_factory=Header)
    format: str = ""
    data: bytes = b""


@dataclass(frozen=True, slots=True, kw_only=True)
class CameraInfo(Message):
    """sensor_msgs/msg/CameraInfo: K (3x3), R (3x3), P (3x4) row-major, D for ``plumb_bob``."""

    __msgtype__: ClassVar[str] = "sensor_msgs/msg/CameraInfo"
    __msgdef__: ClassVar[str] = (
        "std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\n"
        "float64[] d\nfloat64[9] k\nfloat64[9] r\nfloat64[12] p\nuint32 binning_x\n"
        "uint32 binning_y\nsensor_msgs/RegionOfInterest roi\n"
    )
    header: Header = field(default_factory=Header)
    height: int = 0
    width: int = 0
    distortion_model: str = ""
    d: tuple[float, ...] = ()
    k: tuple[float, ...] = (0.0,) * 9
    r: tuple[float, ...] = (0.0,) * 9
    p: tuple[float, ...] = (0.0,) * 12
    binning_x: int = 0
    binning_y: int = 0
    roi: RegionOfInterest = field(default_factory=RegionOfInterest)


@dataclass(frozen=True, slots=True, kw_only=True)
class Odometry(Message):
    """nav_msgs/msg/Odometry: pose in ``header.frame_id`` (odom), twist in ``child_frame_id``."""

    __msgtype__: ClassVar[str] = "nav_msgs/msg/Odometry"
    __msgdef__: ClassVar[str] = (
        "std_msgs/Header header\nstring child_frame_id\n"
        "geometry_msgs/PoseWithCovariance pose\ngeometry_msgs/TwistWithCovariance twist\n"
    )
    header: Header = field(default_factory=Header)
    child_frame_id: str = ""
    pose: PoseWithCovariance = field(default_factory=PoseWithCovariance)
    twist: TwistWithCovariance = field(default_factory=TwistWithCovariance)


@dataclass(frozen=True, slots=True, kw_only=True)
class Path(Message):
    """nav_msgs/msg/Path: a planned path, as move_base publishes its global plan."""

    __msgtype__: ClassVar[str] = "nav_msgs/msg/Path"
    __msgdef__: ClassVar[str] = "std_msgs/Header header\ngeometry_msgs/PoseStamped[] poses\n"
    header: Header = field(default_factory=Header)
    poses: tuple[PoseStamped, ...] = ()


@dataclass(frozen=True, slots=True, kw_only=True)
class Log(Message):
    """rcl_interfaces/msg/Log, the type of ``/rosout``: one mission log line."""

    __msgtype__: ClassVar[str] = "rcl_interfaces/msg/Log"
    __msgdef__: ClassVar[str] = (
        "byte DEBUG=10\nbyte INFO=20\nbyte WARN=30\nbyte ERROR=40\nbyte FATAL=50\n"
        "builtin_interfaces/Time stamp\nuint8 level\nstring name\nstring msg\nstring file\n"
        "string function\nuint32 line\n"
    )
    DEBUG: ClassVar[int] = 10
    INFO: ClassVar[int] = 20
    WARN: ClassVar[int] = 30
    ERROR: ClassVar[int] = 40
    FATAL: ClassVar[int] = 50
    stamp: Time = field(default_factory=Time)
    level: int = 0
    name: str = ""
    msg: str = ""
    file: str = ""
    function: str = ""
    line: int = 0


@dataclass(frozen=True, slots=True, kw_only=True)
class FiducialTransform(Message):
    """fiducial_msgs/msg/FiducialTransform, as aruco_detect fills it.

    ``transform`` is the marker's pose in the camera's optical frame; ``image_error`` the mean
    reprojection error (pixels), ``object_error`` the same error expressed in object space
    (metres), ``fiducial_area`` the area of the detected quadrilateral (pixels^2).
    """

    __msgtype__: ClassVar[str] = "fiducial_msgs/msg/FiducialTransform"
    __msgdef__: ClassVar[str] = (
        "int32 fiducial_id\ngeometry_msgs/Transform transform\nfloat64 image_error\n"
        "float64 object_error\nfloat64 fiducial_area\n"
    )
    fiducial_id: int = 0
    transform: Transform = field(default_factory=Transform)
    image_error: float = 0.0
    object_error: float = 0.0
    fiducial_area: float = 0.0


@dataclass(frozen=True, slots=True, kw_only=True)
class FiducialTransformArray(Message):
    """fiducial_msgs/msg/FiducialTransformArray, the type of ``/fiducial_transforms``."""

    __msgtype__: ClassVar[str] = "fiducial_msgs/msg/FiducialTransformArray"
    __msgdef__: ClassVar[str] = (
        "std_msgs/Header header\nint32 image_seq\nfiducial_msgs/FiducialTransform[] transforms\n"
    )
    header: Header = field(default_factory=Header)
    image_seq: int = 0
    transforms: tuple[FiducialTransform, ...] = ()


@dataclass(frozen=True, slots=True, kw_only=True)
class ArucoMarkers(Message):
    """ros2_aruco_interfaces/msg/ArucoMarkers, the type of ``/aruco_markers`` (ros2_aruco's
    ``aruco_node``): the IDs seen in one camera frame and, in the same order, each marker's
    pose in the camera's optical frame (``header.frame_id``)."""

    __msgtype__: ClassVar[str] = "ros2_aruco_interfaces/msg/ArucoMarkers"
    __msgdef__: ClassVar[str] = (
        "std_msgs/Header header\nint64[] marker_ids\ngeometry_msgs/Pose[] poses\n"
    )
    header: Header = field(default_factory=Header)
    marker_ids: tuple[int, ...] = ()
    poses: tuple[Pose, ...] = ()


@dataclass(frozen=True, slots=True, kw_only=True)
class KeyValue(Message):
    """diagnostic_msgs/msg/KeyValue."""

    __msgtype__: ClassVar[str] = "diagnostic_msgs/msg/KeyValue"
    __msgdef__: ClassVar[str] = "string key\nstring value\n"
    key: str = ""
    value: str = ""


@dataclass(frozen=True, slots=True, kw_only=True)
class DiagnosticStatus(Message):
    """diagnostic_msgs/msg/DiagnosticStatus: a named outcome with a level and key/value details.

    Used for navigation goal outcomes (succeeded / failed with a reason), where a ROS 2 type with a
    free-text reason is needed and action_msgs/GoalStatus has none.
    """

    __msgtype__: ClassVar[str] = "diagnostic_msgs/msg/DiagnosticStatus"
    __msgdef__: ClassVar[str] = (
        "byte OK=0\nbyte WARN=1\nbyte ERROR=2\nbyte STALE=3\n"
        "byte level\nstring name\nstring message\nstring hardware_id\n"
        "diagnostic_msgs/KeyValue[] values\n"
    )
    OK: ClassVar[int] = 0
    WARN: ClassVar[int] = 1
    ERROR: ClassVar[int] = 2
    STALE: ClassVar[int] = 3
    level: int = 0
    name: str = ""
    message: str = ""
    hardware_id: str = ""
    values: tuple[KeyValue, ...] = ()


@dataclass(frozen=True, slots=True, kw_only=True)
class MapMetaData(Message):
    """nav_msgs/msg/MapMetaData: the grid's resolution (m/cell), size and origin in ``map``."""

    __msgtype__: ClassVar[str] = "nav_msgs/msg/MapMetaData"
    __msgdef__: ClassVar[str] = (
        "builtin_interfaces/Time map_load_time\nfloat32 resolution\nuint32 width\n"
        "uint32 height\ngeometry_msgs/Pose origin\n"
    )
    map_load_time: Time = field(default_factory=Time)
    resolution: float = 0.0
    width: int = 0
    height: int = 0
    origin: Pose = field(default_factory=Pose)


@dataclass(frozen=True, slots=True, kw_only=True)
class OccupancyGrid(Message):
    """nav_msgs/msg/OccupancyGrid, the type of ``/map`` (what map_server publishes, latched).

    ``data`` holds the ``int8`` cells row-major from the origin (row = y, column = x) as raw
    bytes: 0 free, 100 occupied, 255 (-1 as int8) unknown.
    """

    __msgtype__: ClassVar[str] = "nav_msgs/msg/OccupancyGrid"
    __msgdef__: ClassVar[str] = "std_msgs/Header header\nnav_msgs/MapMetaData info\nint8[] data\n"
    header: Header = field(default_factory=Header)
    info: MapMetaData = field(default_factory=MapMetaData)
    data: bytes = b""


MESSAGE_TYPES: tuple[type[Message], ...] = (
    Time,
    Duration,
    Header,
    String,
    Bool,
    Vector3,
    Quaternion,
    Point,
    Pose,
    PoseStamped,
    PoseArray,
    PoseWithCovariance,
    PoseWithCovarianceStamped,
    Transform,
    TransformStamped,
    Twist,
    TwistWithCovariance,
    TFMessage,
    RegionOfInterest,
    CompressedImage,
    CameraInfo,
    Odometry,
    Path,
    Log,
    FiducialTransform,
    FiducialTransformArray,
    ArucoMarkers,
    KeyValue,
    DiagnosticStatus,
    MapMetaData,
    OccupancyGrid,
)
"""Every message type usar-replay writes, in dependency order."""

_BY_NAME: dict[str, type[Message]] = {cls.__msgtype__: cls for cls in MESSAGE_TYPES}


def message_class(msgtype: str) -> type[Message]:
    """The class for a ROS 2 type name (``pkg/msg/Type``); KeyError if usar-replay has none."""
    return _BY_NAME[msgtype]


# --- field kinds, used by the converters in bag.py and by tests that generate messages ----------

FieldKind = typing.Literal["msg", "msgs", "bytes", "floats", "ints", "float", "int", "bool", "str"]


def field_kinds(cls: type[Message]) -> tuple[tuple[str, FieldKind, Any], ...]:
    """(name, kind, element class or None) for each field of ``cls``, resolved once per class."""
    return _field_kinds(cast(Any, cls))


@functools.cache
def _field_kinds(cls: Any) -> tuple[tuple[str, FieldKind, Any], ...]:
    hints = typing.get_type_hints(cls)
    out: list[tuple[str, FieldKind, Any]] = []
    for f in dataclasses.fields(cls):
        hint = hints[f.name]
        origin = typing.get_origin(hint)
        if origin is tuple:
            elem = typing.get_args(hint)[0]
            if isinstance(elem, type) and issubclass(elem, Message):
                out.append((f.name, "msgs", elem))
            elif elem is int:
                out.append((f.name, "ints", None))
            else:
                out.append((f.name, "floats", None))
        elif isinstance(hint, type) and issubclass(hint, Message):
            out.append((f.name, "msg", hint))
        elif hint is bytes:
            out.append((f.name, "bytes", None))
        elif hint is float:
            out.append((f.name, "float", None))
        elif hint is bool:
            out.append((f.name, "bool", None))
        elif hint is int:
            out.append((f.name, "int", None))
        elif hint is str:
            out.append((f.name, "str", None))
        else:  # pragma: no cover - a programming error in this module
            raise TypeError(f"{cls.__name__}.{f.name}: unsupported field type {hint!r}")
    return tuple(out)
