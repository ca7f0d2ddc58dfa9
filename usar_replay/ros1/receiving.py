"""The bridge's receiving side: what the graph publishes on ``/tf``, ``/tf_static``, the robots'
``cmd_vel`` and ``/rosout``, kept as usar values until the tick ends, then handed over sorted.

rospy calls the callbacks on its threads, one per connection, in whatever order the machine
runs them; the tick's outputs must not depend on that, so :meth:`Inbox.take` sorts what arrived
by (topic, publishing node). One node's messages on one topic keep their order (one TCP
connection, one thread), and a stable sort keeps it.

One job, apart from the tick loop (:mod:`.bridge`) and the publishing side (:mod:`.publishing`).
"""

from __future__ import annotations

import threading
from collections.abc import Sequence
from typing import Any

from usar_replay.core import contract, msgs
from usar_replay.ros1.latched import Redelivery

__all__ = ["Inbox", "caller"]


def caller(msg: Any) -> str:
    """The node that published ``msg`` (its connection header's ``callerid``)."""
    header = getattr(msg, "_connection_header", None) or {}
    return str(header.get("callerid", ""))


class Inbox:
    """What the graph published since the last :meth:`take`; ``own_node`` is the bridge's
    name, whose own ``/tf`` and ``/rosout`` are not the graph's outputs."""

    def __init__(self, own_node: str) -> None:
        self.own_node = own_node
        self._lock = threading.Lock()
        self._items: list[tuple[str, str, msgs.Message]] = []
        self.latched = Redelivery()
        """Drops a latched message a second connection to its publisher sent again
        (:mod:`.latched`)."""

    def subscribe(self, robots: list[str]) -> None:
        """rospy's subscribers, in the bridge's start-up order (rospy must be initialised)."""
        import rospy
        from geometry_msgs.msg import Twist
        from tf2_msgs.msg import TFMessage

        rospy.Subscriber(
            contract.TF, TFMessage, self.on_tf, callback_args=contract.TF, tcp_nodelay=True
        )
        rospy.Subscriber(
            contract.TF_STATIC, TFMessage, self.on_tf, callback_args=contract.TF_STATIC
        )
        # raw bytes, read here (:func:`.convert.log_from_ros1_bytes`); of Log's type only, as
        # rospy's own checks would have it (a publisher of another type on /rosout is ignored)
        rospy.Subscriber(contract.ROSOUT, rospy.AnyMsg, self.on_log, tcp_nodelay=True)
        for robot in robots:
            topic = contract.cmd_vel(robot)
            rospy.Subscriber(topic, Twist, self.on_twist, callback_args=topic, tcp_nodelay=True)

    def _ours(self, msg: Any) -> bool:
        header = getattr(msg, "_connection_header", None) or {}
        return bool(header.get("callerid") == self.own_node)

    def _put(self, topic: str, msg: Any, value: msgs.Message) -> None:
        if not self.latched.fresh(topic, getattr(msg, "_connection_header", None), value):
            return
        with self._lock:
            self._items.append((topic, caller(msg), value))

    def on_tf(self, msg: Any, topic: str) -> None:
        """A ``tf2_msgs/TFMessage`` on ``topic`` (``/tf`` or ``/tf_static``)."""
        if self._ours(msg):
            return
        from usar_replay.ros1.convert import from_ros1

        self._put(topic, msg, from_ros1(msgs.TFMessage, msg))

    def on_twist(self, msg: Any, topic: str) -> None:
        """A ``geometry_msgs/Twist`` on a robot's ``cmd_vel`` (``topic``)."""
        from usar_replay.ros1.convert import from_ros1

        self._put(topic, msg, from_ros1(msgs.Twist, msg))

    def on_log(self, msg: Any) -> None:
        """A ``rosgraph_msgs/Log`` on ``/rosout``, as rospy's ``AnyMsg`` (raw bytes)."""
        from rosgraph_msgs.msg import Log

        from usar_replay.ros1.convert import log_from_ros1_bytes

        header = getattr(msg, "_connection_header", None) or {}
        kind = (header.get("type"), header.get("md5sum"))
        if self._ours(msg) or kind != (Log._type, Log._md5sum):
            return
        value = log_from_ros1_bytes(bytes(msg._buff))
        if value is not None:
            self._put(contract.ROSOUT, msg, value)

    def take(
        self, more: Sequence[tuple[str, str, msgs.Message]] = ()
    ) -> list[tuple[str, msgs.Message]]:
        """What arrived, with ``more`` (the graph's own topics, :mod:`.topic_recorder`), in a
        fixed order: by topic, then publishing node; emptied for the next tick."""
        with self._lock:
            got, self._items = self._items, []
        got += more
        # one node's messages on one topic keep their order (one TCP connection)
        got.sort(key=lambda item: (item[0], item[1]))
        return [(topic, value) for topic, _node, value in got]
