"""Every topic the student's graph publishes, recorded (the bridge's ``rosbag record -a``).

Why: a package's own topics (the explorer's stored markers on ``/explorer/marker_poses``, a
debug counter) are part of what it did; a log without them cannot show the stored markers or
let ``usar echo`` read them. The bridge asks the master which topics exist
(``getSystemState``) before the first ``/clock`` and then in each tick in which the master's
call log (``--master-logger-level debug``: every API call is a line, written before the call
is answered) has grown since the last ask: a topic is advertised by a call to the master, so a
tick without one has nothing new, and the hot path costs one ``stat`` instead of a round trip
through the master (a Python process on the graph's CPU). It subscribes with
``rospy.AnyMsg`` (raw bytes and the connection header: type, ``message_definition``,
``callerid``) to every topic a node of the graph publishes, leaving out usar's own: any
topic the bridge's node publishes or subscribes to
(the simulator's, ``/clock``, ``/tf``, ``cmd_vel``, ``/rosout``, the move_base action topics),
and ``/rosout_agg``. A latched topic's last message arrives on connecting.

A message of a type usar has a value for (``geometry_msgs/PoseArray``, ``std_msgs/String``) is
converted to it (so the log's ROS 2 readers, the status line and the report see it); any
other stays in its own ROS 1 bytes (:class:`usar_replay.core.ros1msg.Ros1Message`). What
arrived within one tick is handed back sorted by (topic, publishing node), arrival order
kept within one node's topic, so the order does not depend on rospy's threads.
"""

from __future__ import annotations

import os
import threading
import time
import xmlrpc.client
from pathlib import Path
from typing import Any

from usar_replay.core import cdr, msgs, ros1msg
from usar_replay.ros1.latched import Redelivery

__all__ = ["TopicRecorder", "wire_item"]

_SKIPPED = frozenset({"/rosout_agg"})


def wire_item(topic: str, value: msgs.Message) -> tuple[str, str, bytes]:
    """One output of the tick protocol: a usar value as CDR, a ROS 1 message packed."""
    if isinstance(value, ros1msg.Ros1Message):
        wire_type, data = ros1msg.pack(value)
        return topic, wire_type, data
    return topic, type(value).__msgtype__, cdr.encode(value)


class TopicRecorder:
    """The bridge's subscriptions to the graph's own topics (see the module doc)."""

    def __init__(self, node: str, master_uri: str, master_log: Path | None = None) -> None:
        self.node = node
        self._master = xmlrpc.client.ServerProxy(master_uri)
        self._log = master_log
        """The master's call log (None: ask the master every time)."""
        self._log_seen: tuple[int, int] | None = None
        self._lock = threading.Lock()
        self._latched = Redelivery()
        self._subs: dict[str, Any] = {}
        self._arrived: list[tuple[str, str, int, msgs.Message]] = []
        self._count = 0
        self._publishers: dict[str, int] = {}
        self._registrations: frozenset[tuple[str, str, str]] | None = None
        self.registered = False
        """The last :meth:`discover` found a topic registration (a publisher or subscriber of
        any node) that was not there at the one before: a connection may be on its way."""

    def subscribed(self, topic: str) -> bool:
        """Whether a node other than the bridge subscribed to ``topic`` at the last
        :meth:`discover` (the master's registrations)."""
        return any(
            kind == "sub" and t == topic and name != self.node
            for kind, t, name in self._registrations or ()
        )

    @property
    def topics(self) -> list[str]:
        """The topics subscribed so far, sorted."""
        return sorted(self._subs)

    def _log_state(self) -> tuple[int, int] | None:
        if self._log is None:
            return None
        try:
            st = os.stat(self._log)
        except OSError:
            return None
        return st.st_ino, st.st_size

    def discover(self) -> list[str]:
        """Subscribe to every topic the graph publishes that is not usar's own; the topics
        subscribed now (their connections are made by rospy's threads: :meth:`wait_connected`).
        Asks the master only when its call log changed since the last ask (module doc)."""
        import rospy

        new: list[str] = []
        self.registered = False
        before = self._log_state()
        if before is not None and before == self._log_seen:
            return new  # no call reached the master since: no topic was advertised
        reply: Any = self._master.getSystemState(self.node)
        self._log_seen = self._log_state()  # our own call's line included
        state = reply[2]
        publishers, subscribers = state[0], state[1]
        registrations = frozenset(
            (kind, topic, name)
            for kind, entries in (("pub", publishers), ("sub", subscribers))
            for topic, names in entries
            for name in names
        )
        if self._registrations is not None and registrations - self._registrations:
            self.registered = True
        self._registrations = registrations
        ours = {t for t, names in (*publishers, *subscribers) if self.node in names}
        for topic, names in sorted(publishers):
            if topic in self._subs or topic in ours or topic in _SKIPPED:
                continue
            if not any(n != self.node for n in names):
                continue
            self._subs[topic] = rospy.Subscriber(
                topic, rospy.AnyMsg, self._on_message, callback_args=topic, tcp_nodelay=True
            )
            self._publishers[topic] = sum(1 for n in names if n != self.node)
            new.append(topic)
        return new

    def wait_connected(self, cap_s: float) -> bool:
        """Until every subscription is connected to each publisher the master named when it was
        made, or ``cap_s`` wall seconds (pacing only: never part of a message); False then."""
        deadline = time.monotonic() + cap_s
        while time.monotonic() < deadline:
            if all(
                sub.get_num_connections() >= self._publishers.get(topic, 1)
                for topic, sub in self._subs.items()
            ):
                return True
            time.sleep(0.001)
        return False

    def _on_message(self, raw: Any, topic: str) -> None:
        header = getattr(raw, "_connection_header", None) or {}
        if header.get("callerid") == self.node:
            return
        value = _value(str(header.get("type", "")), header, bytes(raw._buff))
        if value is None or not self._latched.fresh(topic, header, value):
            return
        with self._lock:
            self._count += 1
            self._arrived.append((topic, str(header.get("callerid", "")), self._count, value))

    def take(self) -> list[tuple[str, str, msgs.Message]]:
        """What arrived since the last call as (topic, node, value), sorted by (topic, node,
        arrival)."""
        with self._lock:
            got, self._arrived = self._arrived, []
        got.sort(key=lambda item: item[:3])
        return [(topic, node, value) for topic, node, _n, value in got]

    def close(self) -> None:
        for sub in self._subs.values():
            sub.unregister()
        self._subs.clear()


def _value(msgtype: str, header: dict[str, str], data: bytes) -> msgs.Message | None:
    """usar's value where usar has the type, else the message as its ROS 1 bytes."""
    if "/" not in msgtype:
        return None
    try:
        cls = msgs.message_class(ros1msg.ros2_name(msgtype))
    except KeyError:
        cls = None
    if cls is not None:
        try:
            from usar_replay.ros1.convert import from_ros1, ros1_class

            rospy_value = ros1_class(cls.__msgtype__)().deserialize(data)
            return from_ros1(cls, rospy_value)
        except Exception:  # noqa: BLE001 - a same-named type of other fields: kept as bytes
            pass
    return ros1msg.Ros1Message(
        msgtype=msgtype, definition=str(header.get("message_definition", "")), data=data
    )
