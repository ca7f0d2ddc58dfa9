"""ros1/convert: usar's message values <-> rospy's ROS 1 messages (Debian's ROS 1 Python
packages, on ``sys.path`` as the bridge process puts them)."""

from __future__ import annotations

import sys

from usar_replay.core import msgs
from usar_replay.ros1.building import debian


def _ros1() -> None:
    if str(debian.DIST_PACKAGES) not in sys.path:
        sys.path.append(str(debian.DIST_PACKAGES))


def test_messages_convert_both_ways() -> None:
    """usar's values -> rospy's -> usar's is the identity (Time's secs/nsecs, CameraInfo's
    D/K/R/P, a header's seq are the spellings that differ)."""
    _ros1()
    from usar_replay.ros1.convert import from_ros1, to_ros1

    stamp = msgs.Time(sec=12, nanosec=500_000_000)
    values: list[msgs.Message] = [
        msgs.TFMessage(
            transforms=(
                msgs.TransformStamped(
                    header=msgs.Header(stamp=stamp, frame_id="map"),
                    child_frame_id="marker_frame",
                    transform=msgs.Transform(
                        translation=msgs.Vector3(x=1.0, y=-2.0, z=0.5),
                        rotation=msgs.Quaternion(z=0.6, w=0.8),
                    ),
                ),
            )
        ),
        msgs.CameraInfo(
            header=msgs.Header(stamp=stamp, frame_id="cam"),
            height=240,
            width=320,
            distortion_model="plumb_bob",
            d=(0.0,) * 5,
            k=tuple(float(i) for i in range(9)),
        ),
        msgs.Twist(angular=msgs.Vector3(z=0.1)),
    ]
    for value in values:
        ros1 = to_ros1(value)
        assert from_ros1(type(value), ros1) == value
    assert to_ros1(values[1]).K[4] == 4.0
    assert to_ros1(values[0]).transforms[0].header.stamp.nsecs == 500_000_000


def test_rosout_levels_and_names_come_back_as_rcl_log() -> None:
    _ros1()
    import io

    from rosgraph_msgs.msg import Log as Log1

    from usar_replay.ros1.convert import log_from_ros1_bytes, ros1_class

    def wire(value: object) -> bytes:
        buff = io.BytesIO()
        value.serialize(buff)  # type: ignore[attr-defined]
        return buff.getvalue()

    assert ros1_class("geometry_msgs/msg/Twist").__name__ == "Twist"
    value = Log1(level=Log1.WARN, name="/explorer", msg="explorer: stuck", file="e.cpp", line=7)
    value.header.stamp.secs, value.header.stamp.nsecs = 12, 500
    value.topics = ["/rosout", "/explorer/cmd_vel"]
    got = log_from_ros1_bytes(wire(value))
    assert got is not None and got.level == msgs.Log.WARN
    assert (got.stamp.sec, got.stamp.nanosec) == (12, 500)
    assert (got.name, got.msg, got.file, got.line) == ("explorer", "explorer: stuck", "e.cpp", 7)
    weird = log_from_ros1_bytes(wire(Log1(level=3, function="f")))
    assert weird is not None and weird.level == msgs.Log.INFO  # not a ROS 1 level
    assert weird.function == "f"
    # whatever the bytes, the same fields as rospy's own deserialize, or None where it fails
    bad = wire(Log1(level=Log1.ERROR, msg="caf\u00e9", topics=["a"])).replace(b"\xc3", b"\xff")
    for data in (bad, *(bad[:k] for k in range(len(bad)))):  # every truncation too
        import genpy

        try:
            ref = Log1().deserialize(data)
        except genpy.DeserializationError:  # rospy drops the message
            assert log_from_ros1_bytes(data) is None
            continue
        mine = log_from_ros1_bytes(data)
        assert mine is not None and (mine.msg, mine.line) == (ref.msg, ref.line)
        assert (mine.name, mine.file, mine.function) == (ref.name, ref.file, ref.function)
