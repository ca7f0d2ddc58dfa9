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
run's few sockets; the sandbox gives the run's namespace a table of its own), and the idle
check asks on every wait (:mod:`.quiescence`). Where a kernel refuses that request, one dump
per family.

What is asked: TCP and UDP over IPv4 and IPv6 (``inet_diag_req_v2``: ``idiag_rqueue`` is what
the owner has not read, ``idiag_wqueue`` what the peer has not acknowledged) and unix sockets
(``unix_diag_req`` with ``UDIAG_SHOW_RQLEN``). TCP sockets in CLOSE-WAIT (a keep-alive
connection the peer closed; XML-RPC leaves them) and TIME-WAIT (no owner) are not asked for.
A listening socket's receive queue is its backlog of connections not yet accepted: waiting too
(:meth:`SockDiag.busy`, the idle check's question, finds those another way: see there).
"""

from __future__ import annotations

import contextlib
import errno
import functools
import itertools
import os
import re
import socket
import struct
from collections.abc import Collection, Iterable, Iterator
from dataclasses import dataclass

import numpy as np

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
_COUNTS = re.compile(rb"(?:used|inuse) (\d+)")
_INET_FIELDS = struct.Struct("=xB54xII4xI")
"""What :meth:`SockDiag.busy` reads of an ``inet_diag_msg``: state, rqueue, wqueue, inode."""


@functools.cache
def _records(size: int) -> np.dtype[np.void]:
    """A netlink message of ``size`` bytes holding one ``inet_diag_msg``, as numpy reads a
    run of them: the header's length, type and sequence, then state, rqueue, wqueue, inode."""
    head = _NLMSG.size
    return np.dtype(
        {
            "names": ["length", "kind", "seq", "state", "rq", "wq", "ino"],
            "formats": ["<u4", "<u2", "<u4", "u1", "<u4", "<u4", "<u4"],
            "offsets": [0, 4, 8, head + 1, head + 56, head + 60, head + 68],
            "itemsize": size,
        }
    )


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
        try:
            self._sockstat = os.open("/proc/net/sockstat", os.O_RDONLY)
        except OSError:
            self._sockstat = -1
        self._census_seen: tuple[bytes, ...] | None = None
        self._udp = True
        """The namespace had UDP sockets when its census last moved (:meth:`busy`)."""
        self._unix = True
        """The namespace had unix sockets :meth:`busy` was not told to ignore then."""

    def close(self) -> None:
        self._sock.close()
        if self._sockstat >= 0:
            with contextlib.suppress(OSError):
                os.close(self._sockstat)
            self._sockstat = -1

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
        out = []
        for data, off, _ in self._tcp_raw(states):
            _f, state, _t, _r, _exp, rq, wq, _uid, ino = _INET_MSG.unpack_from(data, off)
            out.append(SockQueue(ino, "tcp", state, rq, wq))
        return out

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

    def busy(self, ignore: Collection[int] = ()) -> tuple[dict[int, int], frozenset[int]]:
        """What :meth:`all` says, as the idle check needs it, at a fraction of the cost (it
        asks on every wait, twice a tick): the sockets with bytes waiting (inode -> bytes, as
        :attr:`SockQueue.waiting` counts them), and the inodes of the established TCP
        connections. ``ignore``: unix sockets that hold nothing while it asks (the idle check's
        own socket pair).

        What it leaves out, and why that loses nothing:

        - Listening TCP sockets. A connection not yet accepted is in the table of established
          ones with the bytes its peer sent (a ROS connection's header comes first), and the
          listeners' table is one all namespaces share: walking it was half a dump.
        - UDP and unix sockets while the namespace has none (but ``ignore``): which it has is
          asked again whenever ``/proc/net/sockstat``'s counts of the namespace's sockets move
          (a dump walks every bucket of the namespace's table, even an empty one: some 40
          microseconds for unix sockets).

        The TCP records are read where they lie in the kernel's answer (no copy, no object per
        socket)."""
        waiting: dict[int, int] = {}
        established: set[int] = set()
        self._tcp_table(waiting, established)
        census = self._census()
        udp: Iterable[SockQueue]
        unix: Iterable[SockQueue]
        if census is None or census != self._census_seen:
            self._census_seen = census
            udp, unix = list(self._udp_queues()), list(self.unix())  # read below too
            self._udp, self._unix = bool(udp), any(q.inode not in ignore for q in unix)
        else:
            udp = self._udp_queues() if self._udp else ()
            unix = self.unix() if self._unix else ()
        for q in itertools.chain(udp, unix if self._unix else ()):
            if q.rqueue > 0:
                waiting[q.inode] = q.rqueue
        return waiting, frozenset(established)

    def _tcp_table(self, waiting: dict[int, int], established: set[int]) -> None:
        """:meth:`busy`'s TCP part, into ``waiting`` and ``established``. A run of records of
        one size (the kernel writes every TCP socket's record alike) is read as one numpy
        array: a ROS graph has some sixty connections, and reading them one by one was half
        of every idle check's dump."""
        fields = _INET_FIELDS.unpack_from
        for data, at, count in self._tcp_raw(TCP_STATES & ~(1 << TCP_LISTEN), runs=True):
            if count > 1:
                size = _NLMSG.unpack_from(data, at - _NLMSG.size)[0]
                table = np.frombuffer(data, _records((size + 3) & ~3), count, at - _NLMSG.size)
                established.update(table["ino"][table["state"] == TCP_ESTABLISHED].tolist())
                queued = table["rq"].astype(np.int64) + table["wq"]
                for i in np.flatnonzero(queued).tolist():
                    waiting[int(table["ino"][i])] = int(queued[i])
                continue
            state, rq, wq, ino = fields(data, at)
            if state == TCP_ESTABLISHED:
                established.add(ino)
            if rq + wq > 0:
                waiting[ino] = rq + wq

    def _udp_queues(self) -> Iterator[SockQueue]:
        for family in (socket.AF_INET, socket.AF_INET6):
            yield from self.inet(family, socket.IPPROTO_UDP, 0xFFFFFFFF)

    def _census(self) -> tuple[bytes, ...] | None:
        """The namespace's socket counts (``sockets: used`` and each protocol's ``inuse`` in
        ``/proc/net/sockstat``, which counts the caller's network namespace only); None where
        it cannot be read (then UDP and unix sockets are asked every time)."""
        if self._sockstat < 0:
            return None
        try:
            return tuple(_COUNTS.findall(os.pread(self._sockstat, 1024, 0))) or None
        except OSError:
            return None

    def _tcp_raw(self, states: int, runs: bool = False) -> Iterator[tuple[bytes, int, int]]:
        """The TCP records of IPv4 and IPv6 as :meth:`_dump_raw` gives them, from one dump
        where the kernel allows."""
        if self._one_tcp_dump:
            req = _INET_REQ_V1.pack(socket.AF_INET, 0, 0, 0, states, 0)
            try:
                yield from self._dump_raw(req, TCPDIAG_GETSOCK, _INET_MSG.size, runs)
                return
            except OSError:
                self._one_tcp_dump = False  # refused (before any record): one dump per family
        for family in (socket.AF_INET, socket.AF_INET6):
            request = _INET_REQ.pack(family, socket.IPPROTO_TCP, 0, 0, states)
            yield from self._dump_raw(request, SOCK_DIAG_BY_FAMILY, _INET_MSG.size, runs)

    def _dump(self, request: bytes, kind: int = SOCK_DIAG_BY_FAMILY) -> Iterator[bytes]:
        """The records of one dump, each body a copy."""
        for data, off, _ in self._dump_raw(request, kind, 0):
            length = _NLMSG.unpack_from(data, off - _NLMSG.size)[0]
            yield data[off : off - _NLMSG.size + length]

    def _dump_raw(
        self, request: bytes, kind: int, least: int, runs: bool = False
    ) -> Iterator[tuple[bytes, int, int]]:
        """The records of one dump as (a buffer the kernel answered, where the record's body
        starts, 1), those shorter than ``least`` bytes left out. With ``runs``, several
        records in a row of the same size, type and sequence come as one, their count last
        (:meth:`_run`). Raises :class:`OSError` before any record where the kernel refused
        the request."""
        self._seq += 1
        header = _NLMSG.pack(
            _NLMSG.size + len(request),
            kind,
            NLM_F_REQUEST | NLM_F_DUMP,
            self._seq,
            0,
        )
        self._sock.send(header + request)
        head = _NLMSG.size
        while True:
            data = self._sock.recv(65536)
            off, size = 0, len(data)
            while off + head <= size:
                count = self._run(data, off, kind, least) if runs else 0
                if count > 1:
                    yield data, off + head, count
                    off += count * ((_NLMSG.unpack_from(data, off)[0] + 3) & ~3)
                    continue
                length, got, _flags, seq, _pid = _NLMSG.unpack_from(data, off)
                if length < head or off + length > size:
                    return
                at = off + head
                off += (length + 3) & ~3
                if seq != self._seq:
                    continue
                if got == NLMSG_DONE:
                    return
                if got == NLMSG_ERROR:
                    code = (
                        -struct.unpack_from("=i", data, at)[0] if length >= head + 4 else errno.EIO
                    )
                    if code in (0, errno.ENOENT):  # no such family/protocol here: none
                        return
                    raise OSError(code, f"sock_diag: {os.strerror(code)}")
                if length - head >= least:
                    yield data, at, 1

    def _run(self, data: bytes, off: int, kind: int, least: int) -> int:
        """How many messages from ``off`` on are records of this dump (type ``kind``, this
        sequence) of the size of the first, at least ``least`` bytes of body each: checked
        all at once (0 or 1: read the first alone)."""
        length = _NLMSG.unpack_from(data, off)[0]
        step = (length + 3) & ~3
        if length < _NLMSG.size + max(least, _INET_MSG.size):
            return 0
        count = (len(data) - off) // step
        if count < 2:
            return 0
        table = np.frombuffer(data, _records(step), count, off)
        ok = (table["length"] == length) & (table["kind"] == kind) & (table["seq"] == self._seq)
        return count if bool(ok.all()) else int(np.argmin(ok))


def waiting(diag: SockDiag, inodes: Collection[int] | None = None) -> list[SockQueue]:
    """The sockets (of ``inodes``, or all of this network namespace) with bytes waiting."""
    return [q for q in diag.all() if q.waiting > 0 and (inodes is None or q.inode in inodes)]
