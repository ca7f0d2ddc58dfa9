"""netlink sock_diag (usar_replay.ros1.pacing.sock_diag): bytes waiting in real sockets of this
process, found by inode, and what does not count (CLOSE-WAIT)."""

from __future__ import annotations

import contextlib
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


def test_one_tcp_dump_finds_both_families_as_one_dump_each_does() -> None:
    # one walk of the kernel's connection table instead of two: the same sockets, queues
    # included, as the per-family dumps (the fallback where a kernel refuses the one dump)
    with socket.create_server(("127.0.0.1", 0)) as v4, SockDiag() as diag:
        servers = [v4]
        # without an IPv6 loopback here, IPv4 alone
        with contextlib.suppress(OSError):
            servers.append(socket.create_server(("::1", 0), family=socket.AF_INET6))
        client = socket.create_connection(servers[-1].getsockname()[:2])
        peer, _ = servers[-1].accept()
        client.sendall(b"z" * 300)
        wanted = {_ino(s) for s in (*servers, client, peer)}
        one = {q for q in diag.tcp() if q.inode in wanted}
        per_family = [
            q
            for family in (socket.AF_INET, socket.AF_INET6)
            for q in diag.inet(family, socket.IPPROTO_TCP)
            if q.inode in wanted
        ]
        assert one == set(per_family)
        assert {q.inode for q in one} == wanted
        assert any(q.inode == _ino(peer) and q.rqueue == 300 for q in one)
        diag._one_tcp_dump = False
        assert {q for q in diag.tcp() if q.inode in wanted} == one
        for s in (*servers[1:], client, peer):
            s.close()
