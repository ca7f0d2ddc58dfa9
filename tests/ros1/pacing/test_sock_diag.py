"""netlink sock_diag (usar_replay.ros1.pacing.sock_diag): bytes waiting in real sockets of this
process, found by inode, and what does not count (CLOSE-WAIT)."""

from __future__ import annotations

import os
import socket

from usar_replay.ros1.pacing.sock_diag import SockDiag, waiting


def _ino(s: socket.socket) -> int:
    return os.fstat(s.fileno()).st_ino


def test_tcp_bytes_wait_until_read_and_a_backlog_counts() -> None:
    with socket.create_server(("127.0.0.1", 0)) as server, SockDiag() as diag:
        client = socket.create_connection(server.getsockname())
        inodes = {_ino(server), _ino(client)}
        assert [q.kind for q in waiting(diag, inodes)] == ["tcp"]  # the connection not accepted
        peer, _ = server.accept()
        inodes.add(_ino(peer))
        assert waiting(diag, inodes) == []
        client.sendall(b"x" * 1000)
        (q,) = waiting(diag, inodes)
        assert (q.inode, q.rqueue) == (_ino(peer), 1000)
        assert peer.recv(1000, socket.MSG_WAITALL) == b"x" * 1000
        assert waiting(diag, inodes) == []
        # the peer closes with bytes unread on our side: CLOSE-WAIT does not count
        peer.sendall(b"y" * 10)
        peer.close()
        assert client.recv(1, socket.MSG_PEEK) == b"y"  # the bytes and the FIN are here
        assert waiting(diag, {_ino(client)}) == []
        everything = diag.inet(socket.AF_INET, socket.IPPROTO_TCP, 0xFFFFFFFF)
        (closed,) = [q for q in everything if q.inode == _ino(client)]
        assert closed.state == 8 and closed.rqueue >= 10  # CLOSE-WAIT (the FIN counts 1)
        client.close()


def test_unix_socketpair_bytes_wait_until_read() -> None:
    a, b = socket.socketpair()
    with a, b, SockDiag() as diag:
        inodes = {_ino(a), _ino(b)}
        assert waiting(diag, inodes) == []
        a.sendall(b"hello")
        found = {q.inode: q for q in waiting(diag, inodes)}
        assert found[_ino(b)].rqueue == 5
        assert b.recv(16) == b"hello"
        assert waiting(diag, inodes) == []


def test_all_lists_sockets_of_this_namespace() -> None:
    with socket.create_server(("127.0.0.1", 0)) as server, SockDiag() as diag:
        assert _ino(server) in {q.inode for q in diag.all()}
