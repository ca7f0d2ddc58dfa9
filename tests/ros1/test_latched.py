"""A latched message sent again on a publisher's second connection is dropped, once; a value
sent again on the same connection, or by a publisher that does not latch, is kept."""

from __future__ import annotations

import math

from usar_replay.core import msgs
from usar_replay.ros1.latched import Redelivery


def _header(node: str, latching: str = "1") -> dict[str, str]:
    return {"callerid": node, "latching": latching}


def test_the_latch_sent_again_on_a_new_connection_is_dropped() -> None:
    guard = Redelivery()
    first, second = _header("/explorer"), _header("/explorer")
    line = b"explorer up"
    assert guard.fresh("/rosout", first, line)
    assert not guard.fresh("/rosout", second, line)  # rospy's second connection: the latch
    assert guard.fresh("/rosout", second, b"next")
    assert guard.fresh("/rosout", second, b"next")  # the same value again, same connection
    assert guard.dropped == 1


def test_what_is_not_a_latched_copy_is_kept() -> None:
    guard = Redelivery()
    one, two = _header("/a", "0"), _header("/a", "0")
    assert guard.fresh("/t", one, b"x") and guard.fresh("/t", two, b"x")  # not latching
    a, b = _header("/b"), _header("/b")
    assert guard.fresh("/t", a, b"x") and guard.fresh("/t", b, b"y")  # another value
    c = _header("/c")
    assert guard.fresh("/t", c, b"x") and guard.fresh("/u", _header("/c"), b"x")  # topic
    assert guard.fresh("/t", _header("/d"), b"x")  # another node
    assert guard.dropped == 0


def test_a_value_with_a_nan_equals_its_own_copy() -> None:
    guard = Redelivery()
    value = msgs.Vector3(x=math.nan, y=0.0, z=0.0)
    assert guard.fresh("/v", _header("/n"), value)
    assert not guard.fresh("/v", _header("/n"), msgs.Vector3(x=math.nan, y=0.0, z=0.0))


def test_connecting_to_one_publisher_is_one_thread_at_a_time() -> None:
    """Two threads connect to one publisher (rospy's registration reply and publisherUpdate):
    the second waits for the first, and finds its connection made; another publisher's
    connecting is not held up."""
    import threading

    from usar_replay.ros1.latched import one_connection_per_publisher

    class Handler:
        def __init__(self) -> None:
            self.connected: set[tuple[str, str]] = set()
            self.made: list[tuple[str, str]] = []
            self.inside = 0
            self.most_inside = 0
            self.lock = threading.Lock()
            self.release = threading.Event()

        def _connect_topic(self, topic: str, uri: str) -> tuple[int, str, int]:
            with self.lock:
                if (topic, uri) in self.connected:
                    return 1, "already connected", 0
                self.inside += 1
                self.most_inside = max(self.most_inside, self.inside)
            self.release.wait(5.0)  # the handshake, while the other thread races
            with self.lock:
                self.inside -= 1
                self.connected.add((topic, uri))
                self.made.append((topic, uri))
            return 1, "connected", 1

    one_connection_per_publisher(Handler)
    one_connection_per_publisher(Handler)  # idempotent: one wrapper
    h = Handler()
    same = [threading.Thread(target=h._connect_topic, args=("/rosout", "http://a:1/"))
            for _ in range(2)]
    other = threading.Thread(target=h._connect_topic, args=("/rosout", "http://b:1/"))
    for t in (*same, other):
        t.start()
    deadline = threading.Event()
    for _ in range(500):  # until the other publisher's thread is inside with the first one
        if h.most_inside >= 2:
            break
        deadline.wait(0.01)
    h.release.set()
    for t in (*same, other):
        t.join(5.0)
    assert sorted(h.made) == [("/rosout", "http://a:1/"), ("/rosout", "http://b:1/")]
    assert h.most_inside == 2  # a and b at once; never a twice
