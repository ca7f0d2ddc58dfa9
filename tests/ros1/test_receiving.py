"""ros1/receiving: what the graph publishes, from rospy's callbacks (real messages of Debian's
ROS 1 packages, with the connection header rospy sets), handed over per tick in a fixed order
whatever order rospy's threads ran in. (Subscribed through a running master:
tests/ros1/test_record.py.)"""

from __future__ import annotations

import sys
from typing import Any

import pytest

from usar_replay.core import contract, msgs
from usar_replay.ros1.building import debian
from usar_replay.ros1.receiving import Inbox, caller

BRIDGE = "/usar_sim"


@pytest.fixture(scope="module", autouse=True)
def _ros1() -> None:
    if str(debian.DIST_PACKAGES) not in sys.path:
        sys.path.append(str(debian.DIST_PACKAGES))
    pytest.importorskip("rospy")


def _from(msg: Any, node: str) -> Any:
    msg._connection_header = {"callerid": node}
    return msg


def _raw(msg: Any, node: str) -> Any:
    """``msg`` as rospy's ``AnyMsg`` hands it over: its bytes and the connection header."""
    import io

    import rospy

    buff = io.BytesIO()
    msg.serialize(buff)
    raw = rospy.AnyMsg()
    raw.deserialize(buff.getvalue())
    raw._connection_header = {"callerid": node, "type": msg._type, "md5sum": msg._md5sum}
    return raw


def _twist(x: float, node: str) -> Any:
    from geometry_msgs.msg import Twist

    msg = Twist()
    msg.linear.x = x
    return _from(msg, node)


def _tf(child: str, node: str) -> Any:
    from geometry_msgs.msg import TransformStamped
    from tf2_msgs.msg import TFMessage

    tf = TransformStamped()
    tf.header.frame_id = "map"
    tf.child_frame_id = child
    tf.transform.rotation.w = 1.0
    return _from(TFMessage(transforms=[tf]), node)


def test_what_arrived_is_sorted_by_topic_then_node_keeping_each_nodes_order() -> None:
    inbox = Inbox(BRIDGE)
    fast = contract.cmd_vel("explorer")
    inbox.on_twist(_twist(3.0, "/zeta"), fast)
    inbox.on_twist(_twist(1.0, "/alpha"), fast)
    inbox.on_tf(_tf("marker", "/alpha"), contract.TF)
    inbox.on_twist(_twist(2.0, "/alpha"), fast)
    stored = msgs.Twist(linear=msgs.Vector3(x=9.0))
    got = inbox.take([("/aaa_own_topic", "/zeta", stored)])
    assert [topic for topic, _ in got] == ["/aaa_own_topic", fast, fast, fast, contract.TF]
    twists = [v.linear.x for t, v in got if t == fast and isinstance(v, msgs.Twist)]
    assert twists == [1.0, 2.0, 3.0]  # /alpha's two in their order, then /zeta's
    (tf,) = (v for t, v in got if t == contract.TF)
    assert isinstance(tf, msgs.TFMessage)
    assert tf.transforms[0].child_frame_id == "marker"
    assert inbox.take() == []  # emptied for the next tick


def test_the_bridges_own_tf_and_log_are_not_the_graphs_outputs() -> None:
    from rosgraph_msgs.msg import Log

    inbox = Inbox(BRIDGE)
    inbox.on_tf(_tf("base_footprint", BRIDGE), contract.TF_STATIC)
    inbox.on_log(_raw(Log(name=BRIDGE, msg="ours"), BRIDGE))
    inbox.on_log(_raw(Log(name="/explorer", msg="theirs", level=Log.INFO), "/explorer"))
    got = inbox.take()
    assert [topic for topic, _ in got] == [contract.ROSOUT]
    (log,) = (v for _, v in got)
    assert isinstance(log, msgs.Log) and (log.name, log.msg) == ("explorer", "theirs")
    # /rosout is taken in as raw bytes: another type published on it is not read as a log
    from std_msgs.msg import String

    inbox.on_log(_raw(String(data="not a log line"), "/explorer"))
    assert inbox.take() == []
    assert caller(_twist(0.0, "/explorer")) == "/explorer"
    assert caller(object()) == ""
