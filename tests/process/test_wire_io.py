"""process/wire_io: a frame written on a real socket pair, read back by ``recv_bytes``, or cut off
by its deadline when nobody reads."""

from __future__ import annotations

import os
import socket
import threading
from collections.abc import Iterator
from multiprocessing.connection import Connection

import pytest

from usar_replay.process.wire_io import _header, send_within


@pytest.fixture
def pair() -> Iterator[tuple[Connection, Connection]]:
    a, b = socket.socketpair()
    writer, reader = Connection(a.detach()), Connection(b.detach())
    with writer, reader:
        yield writer, reader


def test_a_frame_is_what_send_bytes_writes(pair: tuple[Connection, Connection]) -> None:
    writer, reader = pair
    assert send_within(writer, b"frame", 1.0)
    assert reader.recv_bytes() == b"frame"
    assert send_within(writer, b"", 1.0)
    assert reader.recv_bytes() == b""
    assert os.get_blocking(writer.fileno())  # the socket is left as it was


def test_a_frame_larger_than_the_buffer_arrives_whole_when_read(
    pair: tuple[Connection, Connection],
) -> None:
    writer, reader = pair
    payload = os.urandom(64 * 1024) * 8  # 512 KiB: more than one socket buffer
    # the reader: a thread of this process on the socket's other end
    got: list[bytes] = []
    t = threading.Thread(target=lambda: got.append(reader.recv_bytes()))
    t.start()
    assert send_within(writer, payload, 10.0)
    t.join()
    assert got == [payload]


def test_a_write_to_a_peer_that_reads_nothing_ends_by_its_deadline(
    pair: tuple[Connection, Connection],
) -> None:
    writer, _reader = pair
    big = bytes(range(256)) * 64 * 1024  # 16 MiB: far more than a socket's buffer
    assert not send_within(writer, big, 0.2)
    assert os.get_blocking(writer.fileno())


def test_a_closed_peer_raises(pair: tuple[Connection, Connection]) -> None:
    writer, reader = pair
    reader.close()
    with pytest.raises((BrokenPipeError, ConnectionResetError)):
        send_within(writer, b"x" * 1024 * 1024, 1.0)


def test_the_header_is_send_bytes_header() -> None:
    assert _header(5) == b"\x00\x00\x00\x05"
    assert _header(0x80000000) == b"\xff\xff\xff\xff" + (0x80000000).to_bytes(8, "big")
