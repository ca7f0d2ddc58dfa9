"""Bytes waiting in sockets, asked of the kernel with netlink ``sock_diag``.

Why: the ROS 1 bridge calls a graph idle only when no bytes wait in any of its sockets (a
message on its way between two nodes is a reaction not finished). ``/proc/net/tcp`` says the
same but is formatted text for every socket of the machine, about 4 ms a read; one
``NETLINK_SOCK_DIAG`` dump per family is a few syscalls and binary records (tens of
microseconds), and it covers only the caller's network namespace, which in the sandbox is the
run's own.

TCP is asked in one dump for both IPv4 and IPv6 (the older ``TCPDIAG_GETSOCK`` request, which
the kernel answers with every family): a TCP dump walks the kernel's whole connection table,
which namespaces share (262144 buckets on a large machine, some 0.4 ms a walk, whatever the
run's few sockets), and the idle check asks on every sample (:mod:`.quiescence`). Where a
kernel refuses that request, one dump per family.

What is asked: TCP and UDP over IPv4 and IPv6 (``inet_diag_req_v2``: ``idiag_rqueue`` is what
the owner has not read, ``idiag_wqueue`` what the peer has not acknowledged) and unix sockets
(``unix_diag_req`` with ``UDIAG_SHOW_RQLEN``). TCP sockets in CLOSE-WAIT (a keep-alive
connection the peer closed; XML-RPC leaves them) and TIME-WAIT (no owner) are not asked for.
A listening socket's receive queue is its backlog of connections not yet accepted: waiting too.
"""

from __future__ import annotations

import errno
import os
import socket
import struct
from collections.abc import Collection, Iterable, Iterator
from dataclasses import dataclass

__all__ = ["SockQueue", "SockDiag", "waiting"]

NETLINK_SOCK_DIAG = 4
SOCK_DIAG_BY_FAMILY = 20
TCPDIAG_GETSOCK = 18
"""``inet_diag_req`` (version 1): the kernel dumps TCP sockets of every family for it."""
NLM_F_REQUEST = 0x1
NLM_F_DUMP = 0x300
NLMSG_ERROR = 2
NLMSG_DONE = 3
UDIAG_SHOW_RQLEN = 0x10
UNIX_DIAG_RQLEN = 4
TCP_ESTABLISHED = 1
TCP_LISTEN = 10
_TCP_TIME_WAIT = 6
_TCP_CLOSE_WAIT = 8
TCP_STATES = 0xFFF & ~(1 << _TCP_TIME_WAIT) & ~(1 << _TCP_CLOSE_WAIT)
"""Every TCP state but TIME-WAIT and CLOSE-WAIT (bit n is state n)."""

_NLMSG = struct.Struct("=IHHII")
_INET_REQ = struct.Struct("=BBBBI48x")  # family, protocol, ext, pad, states, inet_diag_sockid
_INET_REQ_V1 = struct.Struct("=BBBB48xII")  # family, src_len, dst_len, ext, sockid, states, dbs
_INET_MSG = struct.Struct("=BBBB48xIIIII")  # ..., expires, rqueue, wqueue, uid, inode
_UNIX_REQ = struct.Struct("=BBHIIIII")  # family, protocol, pad, states, ino, show, cookie[2]
_UNIX_MSG = struct.Struct("=BBBBIII")  # family, type, state, pad, ino, cookie[2]
_RTA = struct.Struct("=HH")


@dataclass(frozen=True, slots=True)
class SockQueue:
    """One socket's queues: bytes (or, listening, connections) not yet taken by its owner."""

    inode: int
    kind: str
    """``tcp``, ``udp`` or ``unix``."""
    state: int
    rqueue: int
    wqueue: int

    @property
    def waiting(self) -> int:
        """What is in flight at this socket: its receive queue, plus, for TCP not listening,
        what was sent and not yet acknowledged (a listening socket's wqueue is its backlog; a
        unix or UDP socket's is the memory of what it sent, which the peer's rqueue counts)."""
        if self.kind != "tcp" or self.state == TCP_LISTEN:
            return self.rqueue
        return self.rqueue + self.wqueue


class SockDiag:
    """One netlink socket, asked again for every dump (keep one per thread)."""

    def __init__(self) -> None:
        self._sock = socket.socket(socket.AF_NETLINK, socket.SOCK_RAW, NETLINK_SOCK_DIAG)
        self._sock.bind((0, 0))
        self._seq = 0
        self._one_tcp_dump = True
        """The kernel answers ``TCPDIAG_GETSOCK`` (until it refused once)."""

    def close(self) -> None:
        self._sock.close()

    def __enter__(self) -> SockDiag:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def inet(self, family: int, protocol: int, states: int = TCP_STATES) -> Iterator[SockQueue]:
        """The TCP (``IPPROTO_TCP``) or UDP (``IPPROTO_UDP``) sockets of ``family``."""
        kind = "tcp" if protocol == socket.IPPROTO_TCP else "udp"
        req = _INET_REQ.pack(family, protocol, 0, 0, states)
        yield from self._inet_records(self._dump(req), kind)

    @staticmethod
    def _inet_records(payloads: Iterable[bytes], kind: str) -> Iterator[SockQueue]:
        for payload in payloads:
            if len(payload) < _INET_MSG.size:
                continue
            _f, state, _t, _r, _exp, rq, wq, _uid, ino = _INET_MSG.unpack_from(payload)
            yield SockQueue(ino, kind, state, rq, wq)

    def tcp(self, states: int = TCP_STATES) -> list[SockQueue]:
        """The TCP sockets of IPv4 and IPv6, from one walk of the kernel's table where it
        allows (the order is the kernel's: IPv4 and IPv6 mixed)."""
        return list(self._inet_records(self._tcp_records(states), "tcp"))

    def _tcp_records(self, states: int) -> list[bytes]:
        """The raw ``inet_diag_msg`` records of :meth:`tcp`."""
        if self._one_tcp_dump:
            req = _INET_REQ_V1.pack(socket.AF_INET, 0, 0, 0, states, 0)
            try:
                return list(self._dump(req, TCPDIAG_GETSOCK))
            except OSError:
                self._one_tcp_dump = False  # refused: one dump per family from now on
        return [
            body
            for family in (socket.AF_INET, socket.AF_INET6)
            for body in self._dump(_INET_REQ.pack(family, socket.IPPROTO_TCP, 0, 0, states))
        ]

    def unix(self) -> Iterator[SockQueue]:
        """The unix sockets (stream, datagram, seqpacket), with their queue lengths."""
        req = _UNIX_REQ.pack(socket.AF_UNIX, 0, 0, 0xFFFFFFFF, 0, UDIAG_SHOW_RQLEN, 0, 0)
        for payload in self._dump(req):
            if len(payload) < _UNIX_MSG.size:
                continue
            _f, _type, state, _p, ino, _c0, _c1 = _UNIX_MSG.unpack_from(payload)
            rq = wq = 0
            off = _UNIX_MSG.size
            while off + _RTA.size <= len(payload):
                length, kind = _RTA.unpack_from(payload, off)
                if length < _RTA.size:
                    break
                if kind == UNIX_DIAG_RQLEN and length >= _RTA.size + 8:
                    rq, wq = struct.unpack_from("=II", payload, off + _RTA.size)
                off += (length + 3) & ~3
            yield SockQueue(ino, "unix", state, rq, wq)

    def all(self) -> Iterator[SockQueue]:
        """TCP over IPv4 and IPv6, UDP over IPv4 and IPv6, then unix sockets."""
        yield from self.tcp()
        for family in (socket.AF_INET, socket.AF_INET6):
            yield from self.inet(family, socket.IPPROTO_UDP, 0xFFFFFFFF)
        yield from self.unix()

    def busy(self) -> tuple[dict[int, int], frozenset[int]]:
        """What :meth:`all` says, as the idle check needs it, at a fraction of the cost (it
        asks on every wait, twice a tick): the sockets with bytes waiting (inode -> bytes, as
        :attr:`SockQueue.waiting` counts them), and the inodes of the established TCP
        connections."""
        waiting: dict[int, int] = {}
        established: set[int] = set()
        unpack = _INET_MSG.unpack_from
        for body in self._tcp_records(TCP_STATES):
            if len(body) >= _INET_MSG.size:
                _f, state, _t, _r, _exp, rq, wq, _uid, ino = unpack(body)
                if state == TCP_ESTABLISHED:
                    established.add(ino)
                queued = rq if state == TCP_LISTEN else rq + wq
                if queued > 0:
                    waiting[ino] = queued
        for family in (socket.AF_INET, socket.AF_INET6):
            for q in self.inet(family, socket.IPPROTO_UDP, 0xFFFFFFFF):
                if q.rqueue > 0:
                    waiting[q.inode] = q.rqueue
        for q in self.unix():
            if q.rqueue > 0:
                waiting[q.inode] = q.rqueue
        return waiting, frozenset(established)

    def _dump(self, request: bytes, kind: int = SOCK_DIAG_BY_FAMILY) -> Iterator[bytes]:
        self._seq += 1
        header = _NLMSG.pack(
            _NLMSG.size + len(request),
            kind,
            NLM_F_REQUEST | NLM_F_DUMP,
            self._seq,
            0,
        )
        self._sock.send(header + request)
        while True:
            data = self._sock.recv(65536)
            off = 0
            while off + _NLMSG.size <= len(data):
                length, kind, _flags, seq, _pid = _NLMSG.unpack_from(data, off)
                if length < _NLMSG.size:
                    return
                body = data[off + _NLMSG.size : off + length]
                off += (length + 3) & ~3
                if seq != self._seq:
                    continue
                if kind == NLMSG_DONE:
                    return
                if kind == NLMSG_ERROR:
                    code = -struct.unpack_from("=i", body)[0] if len(body) >= 4 else errno.EIO
                    if code in (0, errno.ENOENT):  # no such family/protocol here: none
                        return
                    raise OSError(code, f"sock_diag: {os.strerror(code)}")
                yield body


def waiting(diag: SockDiag, inodes: Collection[int] | None = None) -> list[SockQueue]:
    """The sockets (of ``inodes``, or all of this network namespace) with bytes waiting."""
    return [q for q in diag.all() if q.waiting > 0 and (inodes is None or q.inode in inodes)]
