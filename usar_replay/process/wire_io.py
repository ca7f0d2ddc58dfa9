"""Writes on the tick protocol's socket that end by a deadline, never blocking for good.

Why: a peer that stops reading (a mission that sends ``READY`` and then floods frames without
ever reading its socket, or a ROS 1 node that took the bridge's socket and stopped the bridge)
fills the socket's buffer, and a plain ``Connection.send_bytes`` then blocks forever: the
recorder would hang in a *write* where ``--tick-timeout`` only guards reads. Here a frame is
written in non-blocking pieces, each wait for room bounded by what is left of the deadline;
the caller turns a missed deadline into its verdict (``hung``).

The bytes on the wire are exactly :meth:`multiprocessing.connection.Connection.send_bytes`'s
(a 4-byte big-endian length, or ``-1`` and an 8-byte length past 2 GiB, then the payload), so
the reading side is unchanged.
"""

from __future__ import annotations

import os
import select
import struct
import time
from multiprocessing.connection import Connection

__all__ = ["send_within"]


def _header(n: int) -> bytes:
    if n > 0x7FFFFFFF:
        return struct.pack("!i", -1) + struct.pack("!Q", n)
    return struct.pack("!i", n)


def send_within(conn: Connection, payload: bytes, timeout_s: float) -> bool:
    """Send ``payload`` as one frame on ``conn``; False when the peer did not take all of it
    within ``timeout_s`` wall seconds (the frame is then cut: the caller must end the peer).
    A closed peer raises as ``send_bytes`` does (``BrokenPipeError``, ``ConnectionResetError``).
    """
    fd = conn.fileno()
    data = memoryview(_header(len(payload)) + payload)
    deadline = time.monotonic() + max(0.0, timeout_s)
    poller = select.poll()
    poller.register(fd, select.POLLOUT)
    was_blocking = os.get_blocking(fd)
    os.set_blocking(fd, False)
    try:
        while data:
            try:
                n = os.write(fd, data)
            except BlockingIOError:
                n = 0
            data = data[n:]
            if not data:
                break
            left = deadline - time.monotonic()
            if left <= 0:
                return False
            poller.poll(max(1, int(left * 1000)))  # room, an error (the write says) or time
    finally:
        os.set_blocking(fd, was_blocking)
    return True
