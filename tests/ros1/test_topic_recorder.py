"""ros1/topic_recorder: the graph's own topics as they arrive from rospy (real ``rospy.AnyMsg``
values holding genpy-serialised bytes, from Debian's ROS 1 packages), converted where usar has
the type, kept as ROS 1 bytes where it has not, handed back in a fixed order. (Discovery
through a running master: tests/ros1/test_record.py.)"""

from __future__ import annotations

import io
import sys
from typing import Any

import pytest

from usar_replay.core import cdr, msgs, ros1msg
from usar_replay.ros1.building import debian
from usar_replay.ros1.topic_recorder import TopicRecorder, wire_item

BRIDGE = "/usar_sim"


@pytest.fixture(scope="module", autouse=True)
def _ros1() -> None:
    if str(debian.DIST_PACKAGES) not in sys.path:
        sys.path.append(str(debian.DIST_PACKAGES))
    pytest.importorskip("rospy")


def _raw(value: Any, callerid: str, msgtype: str, definition: str = "") -> Any:
    import rospy

    buf = io.BytesIO()
    value.serialize(buf)
    raw = rospy.AnyMsg()
    raw.deserialize(buf.getvalue())
    raw._connection_header = {
        "callerid": callerid,
        "type": msgtype,
        "message_definition": definition or getattr(value, "_full_text", ""),
    }
    return raw


def _pose_array(x: float) -> Any:
    from geometry_msgs.msg import Pose, PoseArray

    arr = PoseArray()
    pose = Pose()
    pose.position.x = x
    pose.orientation.w = 1.0
    arr.poses = [pose]
    return arr


def test_a_known_type_becomes_usars_value_and_an_unknown_one_keeps_its_bytes() -> None:
    from std_msgs.msg import Int32

    rec = TopicRecorder(BRIDGE, "http://127.0.0.1:1/")  # no call reaches the master here
    rec._on_message(_raw(_pose_array(1.5), "/explorer", "geometry_msgs/PoseArray"), "/stored")
    own = _raw(Int32(data=5), "/explorer", "my_pkg/Counter", "int32 data\n")
    rec._on_message(own, "/count")
    rec._on_message(_raw(Int32(data=1), BRIDGE, "std_msgs/Int32"), "/mine")  # usar's own node
    rec._on_message(_raw(Int32(data=1), "/explorer", "nonsense"), "/odd")  # no pkg/Type
    got = rec.take()
    assert [(topic, node) for topic, node, _ in got] == [
        ("/count", "/explorer"),
        ("/stored", "/explorer"),
    ]
    counter, stored = got[0][2], got[1][2]
    assert isinstance(stored, msgs.PoseArray) and stored.poses[0].position.x == 1.5
    assert counter == ros1msg.Ros1Message(
        msgtype="my_pkg/Counter", definition="int32 data\n", data=b"\x05\x00\x00\x00"
    )
    assert rec.take() == []  # handed back once


def test_what_arrived_is_sorted_by_topic_then_node_then_arrival() -> None:
    rec = TopicRecorder(BRIDGE, "http://127.0.0.1:1/")
    for caller, topic, x in [
        ("/follower", "/b", 1.0),
        ("/explorer", "/b", 2.0),
        ("/follower", "/a", 3.0),
        ("/explorer", "/b", 4.0),
    ]:
        rec._on_message(_raw(_pose_array(x), caller, "geometry_msgs/PoseArray"), topic)
    order = [
        (t, node, v.poses[0].position.x)
        for t, node, v in rec.take()
        if isinstance(v, msgs.PoseArray)
    ]
    assert order == [
        ("/a", "/follower", 3.0),
        ("/b", "/explorer", 2.0),
        ("/b", "/explorer", 4.0),
        ("/b", "/follower", 1.0),
    ]


def test_wire_items_are_cdr_or_packed_ros1() -> None:
    twist = msgs.Twist(linear=msgs.Vector3(x=0.1))
    assert wire_item("/cmd", twist) == ("/cmd", twist.__msgtype__, cdr.encode(twist))
    own = ros1msg.Ros1Message(msgtype="p/T", definition="int32 a\n", data=b"\0\0\0\0")
    assert wire_item("/t", own) == ("/t", *ros1msg.pack(own))


def test_the_master_is_asked_only_when_its_call_log_grew(tmp_path: Any) -> None:
    log = tmp_path / "master_api.log"
    log.write_text("registerPublisher('/explorer', '/stored', ...)\n", encoding="utf-8")
    rec = TopicRecorder(BRIDGE, "http://127.0.0.1:1/", log)  # nothing listens on port 1
    with pytest.raises(OSError):
        rec.discover()  # a first ask always reaches the master
    rec._log_seen = rec._log_state()  # as after an answered ask
    assert rec.discover() == []  # the log did not change: the master is not asked
    with log.open("a", encoding="utf-8") as f:
        f.write("registerPublisher('/explorer', '/count', ...)\n")
    with pytest.raises(OSError):
        rec.discover()  # a call reached the master since: asked again
