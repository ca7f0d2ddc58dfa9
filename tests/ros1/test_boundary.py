"""ros1/boundary: the recorder's check of what the bridge sends back, with a ROS 1 package's
own topics and types (real wire bytes: ros1msg's and CDR's)."""

from __future__ import annotations

import pytest

from usar_replay.core import cdr, contract, msgs, ros1msg
from usar_replay.node.boundary_check import MAX_MESSAGE_BYTES, OutputRefused
from usar_replay.node.executor import PublishPolicy
from usar_replay.ros1.boundary import ROS1_FIXED_TYPES, Ros1BoundaryCheck

INT32 = ros1msg.Ros1Message(msgtype="std_msgs/Int32", definition="int32 data\n", data=b"\7\0\0\0")


def _check() -> Ros1BoundaryCheck:
    return Ros1BoundaryCheck(PublishPolicy())


def test_a_package_message_is_kept_as_its_bytes() -> None:
    wire_type, data = ros1msg.pack(INT32)
    [(topic, msgtype, got_data, value)] = _check().check([("/count", wire_type, data)])
    assert (topic, msgtype, got_data, value) == ("/count", wire_type, data, INT32)


def test_the_stored_markers_topic_may_carry_a_pose_array() -> None:
    assert contract.MARKER_POSES not in ROS1_FIXED_TYPES
    arr = msgs.PoseArray(poses=(msgs.Pose(),))
    check = _check()
    [(*_, value)] = check.check([(contract.MARKER_POSES, arr.__msgtype__, cdr.encode(arr))])
    assert value == arr
    with pytest.raises(OutputRefused, match="one topic, one type"):
        check.check([(contract.MARKER_POSES, *ros1msg.pack(INT32))])


def test_bytes_that_do_not_decode_as_their_definition_are_refused() -> None:
    bad = ros1msg.Ros1Message(msgtype="std_msgs/Int32", definition="int32 data\n", data=b"\1")
    with pytest.raises(OutputRefused, match=r"on /count that do not decode as std_msgs/Int32"):
        _check().check([("/count", *ros1msg.pack(bad))])
    with pytest.raises(OutputRefused, match=r"a malformed ROS 1 message on /count"):
        _check().check([("/count", "ros1:std_msgs/Int32", b"\xff\xff")])


def test_one_topic_one_definition() -> None:
    check = _check()
    check.check([("/count", *ros1msg.pack(INT32))])
    other = ros1msg.Ros1Message(
        msgtype="std_msgs/Int32", definition="int32 data  # the count\n", data=b"\7\0\0\0"
    )
    with pytest.raises(OutputRefused, match="/count: a second definition of std_msgs/Int32"):
        check.check([("/count", *ros1msg.pack(other))])


def test_the_course_rules_still_hold() -> None:
    wire_type, data = ros1msg.pack(INT32)
    with pytest.raises(OutputRefused, match="ground truth"):
        _check().check([("/ground_truth/explorer", wire_type, data)])
    with pytest.raises(OutputRefused, match="published by the simulator"):
        _check().check([("/explorer/odom", wire_type, data)])
    huge = ros1msg.Ros1Message(msgtype="x/Y", definition="", data=b"\0" * (MAX_MESSAGE_BYTES + 1))
    with pytest.raises(OutputRefused, match=r"bytes on /big; a message is at most"):
        _check().check([("/big", *ros1msg.pack(huge))])
    with pytest.raises(OutputRefused, match="is too long"):
        _check().check([("/" + "t" * 1000, wire_type, data)])
    with pytest.raises(OutputRefused, match=r"the mission published type 'x/msg/Nope'"):
        _check().check([("/plain", "x/msg/Nope", b"")])  # usar's own types: the parent's check
