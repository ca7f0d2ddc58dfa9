"""Messages: keyword construction, defaults, definitions, and CDR round trips for every type."""

from __future__ import annotations

import dataclasses

import pytest
from hypothesis import given
from hypothesis import strategies as st
from rosbags.typesys import Stores, get_typestore

from usar_replay.core import msgs
from usar_replay.log import bag


def test_keyword_construction_from_the_issue() -> None:
    t = msgs.TransformStamped(
        header=msgs.Header(stamp=msgs.Time(sec=1, nanosec=5), frame_id="map"),
        child_frame_id="a",
        transform=msgs.Transform(translation=msgs.Vector3(x=1.0), rotation=msgs.Quaternion(w=1.0)),
    )
    assert t.header.stamp.ns == 1_000_000_005
    assert t.transform.translation == msgs.Vector3(x=1.0, y=0.0, z=0.0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        t.child_frame_id = "b"  # type: ignore[misc]


def test_ros2_defaults() -> None:
    assert msgs.Quaternion() == msgs.Quaternion(x=0.0, y=0.0, z=0.0, w=1.0)
    info = msgs.CameraInfo()
    assert len(info.k) == 9 and len(info.p) == 12 and info.d == ()
    assert len(msgs.PoseWithCovariance().covariance) == 36
    assert msgs.Log.INFO == 20 and msgs.Log().level == 0


@given(st.integers(min_value=0, max_value=2**62))
def test_time_ns_round_trip(ns: int) -> None:
    t = msgs.Time.from_ns(ns)
    assert 0 <= t.nanosec < 1_000_000_000
    assert t.ns == ns


def test_every_type_name_is_pkg_msg_type() -> None:
    for cls in msgs.MESSAGE_TYPES:
        _pkg, mid, name = cls.__msgtype__.split("/")
        assert mid == "msg" and name == cls.__name__, cls


STANDARD = [
    c
    for c in msgs.MESSAGE_TYPES
    if not c.__msgtype__.startswith(("fiducial_msgs/", "ros2_aruco_interfaces/"))
]


@pytest.mark.parametrize("cls", STANDARD, ids=lambda c: c.__msgtype__)
def test_definitions_match_ros2_humble(cls: type[msgs.Message]) -> None:
    """Our .msg texts describe the same wire layout as ROS 2 Humble's own definitions."""
    humble = get_typestore(Stores.ROS2_HUMBLE)
    assert bag.typestore().fielddefs[cls.__msgtype__] == humble.fielddefs[cls.__msgtype__]


def test_fiducial_definitions_follow_aruco_detect() -> None:
    _, fields = bag.typestore().fielddefs["fiducial_msgs/msg/FiducialTransform"]
    assert [f[0] for f in fields] == [
        "fiducial_id",
        "transform",
        "image_error",
        "object_error",
        "fiducial_area",
    ]
    _, fields = bag.typestore().fielddefs["fiducial_msgs/msg/FiducialTransformArray"]
    assert [f[0] for f in fields] == ["header", "image_seq", "transforms"]
