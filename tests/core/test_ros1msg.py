"""core/ros1msg: a ROS 1 message kept as its own bytes, its wire form, and its decoding."""

from __future__ import annotations

import struct

import pytest

from usar_replay.core import ros1msg

INT32 = ros1msg.Ros1Message(msgtype="std_msgs/Int32", definition="int32 data\n", data=b"\x07\0\0\0")


def test_a_ros1_message_decodes_only_as_its_definition() -> None:
    wire_type, data = ros1msg.pack(INT32)
    assert wire_type == "ros1:std_msgs/Int32"
    assert ros1msg.unpack(wire_type, data) == INT32
    assert ros1msg.decode(INT32.msgtype, INT32.definition, INT32.data).data == 7
    with pytest.raises(Exception, match="size mismatch"):
        ros1msg.decode(INT32.msgtype, INT32.definition, INT32.data + b"\0")


def test_a_definition_with_dependencies_decodes() -> None:
    definition = (
        "geometry_msgs/Point[] points\nstring label\n"
        "================================================================================\n"
        "MSG: geometry_msgs/Point\nfloat64 x\nfloat64 y\nfloat64 z\n"
    )
    data = struct.pack("<I3d3dI", 2, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 2) + b"hi"
    value = ros1msg.decode("my_pkg/Points", definition, data)
    assert [p.z for p in value.points] == [3.0, 6.0]
    assert value.label == "hi"


@pytest.mark.parametrize(
    ("wire_type", "data", "why"),
    [
        ("std_msgs/Int32", b"\0\0\0\0", "not a ROS 1 wire type"),
        ("ros1:std_msgs/Int32", b"\0\0", "shorter than its header"),
        ("ros1:std_msgs/Int32", struct.pack("<I", 100) + b"int32", "definition of 100 bytes"),
        ("ros1:x/Y", struct.pack("<I", ros1msg.MAX_DEFINITION_BYTES + 1), "definition of"),
    ],
)
def test_unpack_refuses_what_pack_did_not_make(wire_type: str, data: bytes, why: str) -> None:
    with pytest.raises(ValueError, match=why):
        ros1msg.unpack(wire_type, data)


def test_ros2_name_adds_msg_once() -> None:
    assert ros1msg.ros2_name("std_msgs/Int32") == "std_msgs/msg/Int32"
    assert ros1msg.ros2_name("std_msgs/msg/Int32") == "std_msgs/msg/Int32"
