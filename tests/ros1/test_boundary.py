"""ros1/boundary: the recorder's check of what the bridge sends back, with a ROS 1 package's
own topics and types (real wire bytes: ros1msg's and CDR's)."""

from __future__ import annotations

import time

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


def _wide(msgtype: str, fields: int) -> ros1msg.Ros1Message:
    """A message of one type of ``fields`` int32 fields (all zero)."""
    definition = "".join(f"int32 f{i}\n" for i in range(fields))
    return ros1msg.Ros1Message(msgtype=msgtype, definition=definition, data=b"\0" * (4 * fields))


def test_a_pathological_definition_is_refused_before_it_is_parsed() -> None:
    """The red team's shape (#33 point 5) under the byte cap: one type of 5,000 fields, ~3 s of
    the recorder's CPU each when parsed; refused now, at once, as the run's verdict."""
    check = _check()
    start = time.process_time()
    for topic in ("/a", "/b", "/c"):
        with pytest.raises(OutputRefused, match=rf"{topic}: .* more than 256 fields"):
            check.check([(topic, *ros1msg.pack(_wide("p/Wide", 5_000)))])
    assert time.process_time() - start < 1.0


def test_a_runs_definitions_share_one_budget() -> None:
    """Four definitions of 250 fields are parsed (each once, however many messages), the fifth
    passes the run's 1,024 fields and ends the run."""
    check = _check()
    for i in range(4):
        for _ in range(3):
            check.check([(f"/t{i}", *ros1msg.pack(_wide(f"p/T{i}", 250)))])
    assert check.parsed.fields == 1000
    with pytest.raises(OutputRefused, match="/t4: the definition of p/T4 is one too many"):
        check.check([("/t4", *ros1msg.pack(_wide("p/T4", 250)))])
