"""One connection per publisher in the bridge's rospy, and a latched message sent twice dropped.

Why: rospy connects a subscriber to a publisher from two threads, the one that registered the
subscription (the master's list of publishers) and the one that answers the master's
``publisherUpdate``. When both find the publisher not yet connected, both connect; the second
connection replaces the first (``_TopicImpl.add_connection``), but a *latched* publisher sends
its last message on every new connection, so the message arrived twice. Whether the two threads
raced is the machine's timing: seen as a node's first ``/rosout`` line (rospy's ``/rosout``
publisher latches) recorded twice in one run of four under load, so the log's bytes differed
from run to run and between engines. ``/tf_static`` and a package's own latched topics are the
same case.

The same race has a second face: when the second connection replaces the first before the
first wrote its handshake, the publishing node logs "Inbound TCP/IP connection failed:
connection from sender terminated before handshake header received" to ``/rosout``, a line one
run has and the next does not (seen in the same test). So :func:`one_connection_per_publisher`
serialises rospy's connecting, per (topic, publisher), in the bridge's own process: the second
thread then finds the connection made and returns, as rospy's own check meant it to. The
package's nodes are not touched (their rospy is theirs).

:class:`Redelivery` stays as the net under it. Its rule, per (topic, publishing node): a
message that arrives on a connection other than the one the last message came by, from a
latching publisher, and equals that last message, is the latch sent again, not a new message.
A publisher that sends the same value again on the same connection is never dropped.
"""

from __future__ import annotations

import threading
from typing import Any

__all__ = ["Redelivery", "one_connection_per_publisher"]

_PATCHED = "_usar_one_connection"


def one_connection_per_publisher(handler: Any = None) -> None:
    """Make rospy's ``ROSHandler._connect_topic`` (every subscriber connection in this process
    goes through it; ``handler``: that class, or another for a test) hold a lock per (topic,
    publisher URI): the second of two racing threads finds the first's connection and returns.
    Idempotent; call before ``rospy.init_node``."""
    if handler is None:
        from rospy.impl import masterslave

        handler = masterslave.ROSHandler
    if getattr(handler, _PATCHED, False):
        return
    connect = handler._connect_topic
    guard = threading.Lock()
    locks: dict[tuple[str, str], threading.Lock] = {}

    def _connect_topic(self: Any, topic: str, pub_uri: str) -> Any:
        with guard:
            lock = locks.setdefault((topic, pub_uri), threading.Lock())
        with lock:  # one publisher's connecting only: a slow publisher holds up no other
            return connect(self, topic, pub_uri)

    handler._connect_topic = _connect_topic
    setattr(handler, _PATCHED, True)


class Redelivery:
    """Remembers each (topic, node)'s last message and the connection it came by."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._last: dict[tuple[str, str], tuple[Any, object]] = {}
        self.dropped = 0
        """Latched copies dropped so far."""

    def fresh(self, topic: str, header: Any, value: object) -> bool:
        """False when ``value`` (on ``topic``, with rospy's connection ``header``: one dict
        object per connection) is a latched message sent again on a new connection."""
        node = str(header.get("callerid", "")) if isinstance(header, dict) else ""
        key = (topic, node)
        with self._lock:
            last = self._last.get(key)
            self._last[key] = (header, value)
            if last is None or last[0] is header or not isinstance(header, dict):
                return True
            if str(header.get("latching", "0")) != "1" or not _same(last[1], value):
                return True
            self.dropped += 1
            return False


def _same(a: object, b: object) -> bool:
    """Equal values; ``repr`` too, so a message with a NaN equals its own copy."""
    if type(a) is not type(b):
        return False
    if isinstance(a, bytes | bytearray):
        return a == b
    try:
        if a == b:
            return True
    except (TypeError, ValueError):  # an array's truth value
        pass
    return repr(a) == repr(b)
