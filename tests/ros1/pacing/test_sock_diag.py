"""netlink sock_diag (usar_replay.ros1.pacing.sock_diag): bytes waiting in real sockets of this
process, found by inode, and what does not count (CLOSE-WAIT)."""

from __future__ import annotations

import contextlib
import os
import socket
import subprocess
import sys

from usar_replay.ros1.netns import isolated_command
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


def test_busy_sees_a_connection_not_yet_accepted_by_its_bytes() -> None:
    # busy() leaves listeners out: the connection waiting to be accepted is in the table of
    # established ones, with the bytes its peer sent before anyone accepted it
    with socket.create_server(("127.0.0.1", 0)) as server, SockDiag() as diag:
        client = socket.create_connection(server.getsockname())
        with client:
            client.sendall(b"header" * 10)
            waiting_now, established = diag.busy()
            assert _ino(client) in established
            assert 60 in waiting_now.values()  # on the side nobody accepted yet
            assert _ino(server) not in waiting_now  # its backlog is not asked for
            peer, _ = server.accept()
            with peer:
                assert peer.recv(60, socket.MSG_WAITALL) == b"header" * 10
                waiting_now, _ = diag.busy()
                assert _ino(peer) not in waiting_now and _ino(client) not in waiting_now


_LATER_SOCKETS = """
import os, socket
from usar_replay.ros1.pacing.sock_diag import SockDiag

def ino(s):
    return os.fstat(s.fileno()).st_ino

ignored_a, ignored_b = socket.socketpair()
with ignored_a, ignored_b, SockDiag() as diag:
    ignore = {ino(ignored_a), ino(ignored_b)}
    ignored_a.sendall(b"request")  # the asker's own pair: what it holds is not counted
    assert diag.busy(ignore)[0] == {}
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as rx:
        rx.bind(("127.0.0.1", 0))
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
            tx.sendto(b"d" * 40, rx.getsockname())
            assert diag.busy(ignore)[0].get(ino(rx), 0) > 0
            rx.recv(100)
            assert ino(rx) not in diag.busy(ignore)[0]
    a, b = socket.socketpair()
    with a, b:
        a.sendall(b"u" * 7)
        assert diag.busy(ignore)[0].get(ino(b)) == 7
print("ok")
"""


def test_busy_finds_udp_and_unix_sockets_made_after_its_first_call() -> None:
    # UDP and unix sockets are asked for only while the namespace has some (but the ignored
    # ones): a socket made later moves /proc/net/sockstat's counts, and busy() looks again.
    # In a network namespace of its own where the machine allows, as a run's is: there the
    # ignored pair is the only socket at the first call
    argv = isolated_command([sys.executable, "-c", _LATER_SOCKETS])
    done = subprocess.run(argv, capture_output=True, text=True, timeout=60, check=False)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "ok"


def test_busy_reads_a_run_of_records_as_they_are_read_one_by_one() -> None:
    """busy() reads a run of same-sized TCP records as one array (sock_diag._run): the bytes
    waiting and the established connections it finds are those of the record-by-record read,
    with sockets waiting at the run's start, middle and end, and one that never waits."""
    with socket.create_server(("127.0.0.1", 0), backlog=32) as server, SockDiag() as diag:
        clients = [socket.create_connection(server.getsockname()) for _ in range(12)]
        peers = [server.accept()[0] for _ in clients]
        with contextlib.ExitStack() as stack:
            for s in clients + peers:
                stack.enter_context(s)
            mine = {_ino(s) for s in clients + peers}
            for n, s in zip((1, 7, 300), (clients[0], peers[5], clients[11]), strict=True):
                s.sendall(b"z" * n)
            waiting_now, established = diag.busy()
            one_by_one = [q for q in diag.tcp() if q.inode in mine]
            assert len(one_by_one) == 24
            expected = {q.inode: q.waiting for q in one_by_one if q.waiting > 0}
            assert {i: n for i, n in waiting_now.items() if i in mine} == expected
            assert sorted(expected.values()) == [1, 7, 300]
            assert established & mine == mine
