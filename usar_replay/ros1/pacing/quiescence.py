"""Is the ROS 1 graph idle: has it finished reacting to the last ``/clock``?

Why: the bridge paces the clock by the graph (docs/ros1.md, "Pacing"): the next tick starts as
soon as the graph is done with this one, not after a fixed wall-time wait, so a run is as fast
as the graph and the same on a loaded machine as on an idle one. The graph is idle when

1. every thread of its processes (the bridge's own included, but not the thread asking) is
   blocked: ``/proc/<pid>/task/<tid>/stat`` state is neither ``R`` nor ``D`` (a thread
   in uninterruptible I/O, writing its output to a file, is still reacting);
2. no bytes wait in any of its sockets (:mod:`.sock_diag`: a message on its way between two
   nodes is a reaction not finished);
3. every thread that was in a *short timed sleep* when the graph first looked idle has woken
   and slept again since (its run count in ``/proc/<pid>/task/<tid>/schedstat`` moved), and no
   other thread ran in between. roscpp's sim-time sleeps (``ros::Rate::sleep``,
   ``Duration::sleep``, timers) poll the clock in 1 ms wall-clock naps: such a node looks idle
   while it has not yet noticed the new ``/clock``. A short timed sleep is a ``nanosleep``/
   ``clock_nanosleep`` of at most :data:`POLL_SLEEP_S` or a timed futex wait (a ``wait_for`` on
   a condition) with at most :data:`SHORT_SLEEP_S` to go, read from
   ``/proc/<pid>/task/<tid>/syscall`` and the timeout it points to in ``/proc/<pid>/mem``
   (the graph is the bridge's descendants: allowed).

Processes are found as the bridge's descendants (``/proc/<pid>/task/<tid>/children``); files
stay open and are read again with ``pread`` (a sample of some 40 threads costs well under a
millisecond).
"""

from __future__ import annotations

import contextlib
import os
import struct
import time
from collections.abc import Collection
from dataclasses import dataclass

from usar_replay.ros1.pacing.sock_diag import SockDiag

TCP_ESTABLISHED = 1

__all__ = [
    "SHORT_SLEEP_S",
    "ChildrenFiles",
    "Quiescence",
    "ThreadState",
    "children_map",
    "descendants",
]

SHORT_SLEEP_S = 0.005
"""A timed wait on a condition with at most this much left counts as a clock poll (roscpp's
sim-time timers wait 1 ms at a time); a longer one is woken by its condition when it matters."""
POLL_SLEEP_S = 0.05
"""A plain sleep of at most this much counts as a poll: nothing but time wakes it (roscpp's
sim-time sleeps nap 1 ms, ``ros::Time::waitForValid`` 10 ms until the first ``/clock``)."""
LONG_WAIT_S = 0.15
"""A timed wait with more than this left at start-up is a wall-clock re-check (see
:meth:`Quiescence.long_waits`); roscpp's own spinners wait 100 ms at a time."""
NAP_S = 0.0002
"""Wall time between two samples (the asking thread sleeps: on one CPU the graph runs then)."""

_NANOSLEEP = 35
_CLOCK_NANOSLEEP = 230
_FUTEX = 202
_FUTEX_WAIT = 0
_FUTEX_WAIT_BITSET = 9
_FUTEX_CLOCK_REALTIME = 256
_TIMER_ABSTIME = 1
_TIMESPEC = struct.Struct("=qq")


@dataclass(frozen=True, slots=True)
class ThreadState:
    """One thread at one sample."""

    running: bool
    runs: int
    """How many times it was given a CPU (schedstat's third field)."""
    polling: bool
    """A package thread in a short timed sleep (it will wake by itself soon and look at the
    clock)."""
    watched: bool
    """A thread of the package or the bridge: when it ran matters. The master's and
    roslaunch's threads only need to be blocked (they wake on their own wall-clock timers, and
    what they do for the graph goes through sockets)."""


def children_map(pid: int) -> dict[int, list[int]]:
    """Every process below ``pid`` (``pid`` included) -> its children (children of every
    thread), read once from ``/proc``: one walk that :func:`descendants` of any process in it
    can share (the bridge walks once per wait, not once for each question)."""
    with ChildrenFiles() as files:
        return files.walk(pid)


class ChildrenFiles:
    """:func:`children_map` with each thread's ``children`` file kept open and read again
    with ``pread``: the bridge walks its tree twice a tick, and opening the files of some 50
    threads each time cost about 1 ms of the tick (ten times the reads)."""

    def __init__(self) -> None:
        self._fds: dict[tuple[int, str], int] = {}

    def walk(self, pid: int) -> dict[int, list[int]]:
        """As :func:`children_map`; the files of threads gone since the last walk closed."""
        out: dict[int, list[int]] = {}
        seen: set[tuple[int, str]] = set()
        todo = [pid]
        while todo:
            p = todo.pop(0)
            kids: list[int] = []
            with contextlib.suppress(OSError):
                for tid in os.listdir(f"/proc/{p}/task"):
                    key = (p, tid)
                    seen.add(key)
                    with contextlib.suppress(OSError):
                        fd = self._fds.get(key)
                        if fd is None:
                            fd = os.open(f"/proc/{p}/task/{tid}/children", os.O_RDONLY)
                            self._fds[key] = fd
                        kids += [int(c) for c in _read_all(fd).split()]
            out[p] = kids
            todo += kids
        for key in set(self._fds) - seen:
            with contextlib.suppress(OSError):
                os.close(self._fds.pop(key))
        return out

    def close(self) -> None:
        for fd in self._fds.values():
            with contextlib.suppress(OSError):
                os.close(fd)
        self._fds.clear()

    def __enter__(self) -> ChildrenFiles:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _read_all(fd: int) -> bytes:
    """The whole file from its start (a thread with many children fills more than a page)."""
    data = os.pread(fd, 4096, 0)
    while len(data) % 4096 == 0 and data:
        more = os.pread(fd, 4096, len(data))
        if not more:
            break
        data += more
    return data


def descendants(pid: int, children: dict[int, list[int]] | None = None) -> list[int]:
    """``pid`` and every process below it (children of every thread), parents first; from
    ``children`` (:func:`children_map` of ``pid`` or of a process above it) when given."""
    tree = children_map(pid) if children is None else children
    out: list[int] = []
    todo = [pid]
    while todo:
        p = todo.pop(0)
        out.append(p)
        todo += tree.get(p, [])
    return out


class _Thread:
    """Open files of one thread, read again with pread."""

    def __init__(self, pid: int, tid: int) -> None:
        base = f"/proc/{pid}/task/{tid}/"
        self.pid = pid
        self.role = "infra"
        self.stat = os.open(base + "stat", os.O_RDONLY)
        try:
            self.schedstat = os.open(base + "schedstat", os.O_RDONLY)
        except OSError:
            os.close(self.stat)
            raise
        try:
            self.syscall: int | None = os.open(base + "syscall", os.O_RDONLY)
        except OSError:
            self.syscall = None

    def close(self) -> None:
        for fd in (self.stat, self.schedstat, self.syscall):
            if fd is not None:
                with contextlib.suppress(OSError):
                    os.close(fd)


class Quiescence:
    """Samples one process tree (see the module docstring); one instance per bridge."""

    def __init__(self, root: int | None = None, own_tid: int | None = None) -> None:
        self.root = os.getpid() if root is None else root
        self.own_tid = own_tid
        self.diag = SockDiag()
        self.children = ChildrenFiles()
        """The tree's walk (:meth:`ChildrenFiles.walk` of :attr:`root`), files kept open."""
        self._threads: dict[int, _Thread] = {}
        self._mem: dict[int, int] = {}
        self._pids: list[int] = []
        self._inodes: set[int] = set()
        self.samples = 0
        """Samples taken (for the bridge's log)."""
        self.untimed: frozenset[int] = frozenset()
        """The package's processes whose main thread was in a wait without a timeout at the
        last sample (:mod:`.shutdown_watch`: roscpp's ``ros::shutdown`` joins its threads so)."""
        self.connected: frozenset[int] = frozenset()
        """The established TCP connections of the namespace at the last sample (a node's
        ``ros::shutdown`` closes its connections: the bridge asks the master then)."""

    def close(self) -> None:
        for t in self._threads.values():
            t.close()
        for fd in self._mem.values():
            with contextlib.suppress(OSError):
                os.close(fd)
        self._threads.clear()
        self._mem.clear()
        self.diag.close()
        self.children.close()

    # -- processes, threads, sockets -------------------------------------------------------------

    def refresh(
        self, package: Collection[int] = (), children: dict[int, list[int]] | None = None
    ) -> list[int]:
        """Find the tree's processes and threads again (new nodes, exited ones); ``package``:
        the pids of the package's processes (the nodes); ``children``: a walk of the tree
        just made (:func:`children_map` of the root)."""
        self._pids = descendants(self.root, children)
        seen: set[int] = set()
        for pid in self._pids:
            with contextlib.suppress(OSError):
                for name in os.listdir(f"/proc/{pid}/task"):
                    tid = int(name)
                    if tid == self.own_tid:
                        continue
                    seen.add(tid)
                    if tid not in self._threads:
                        with contextlib.suppress(OSError):
                            self._threads[tid] = _Thread(pid, tid)
                    if tid in self._threads:
                        role = "bridge" if pid == self.root else "infra"
                        self._threads[tid].role = "node" if pid in package else role
        for tid in set(self._threads) - seen:
            self._threads.pop(tid).close()
        for pid in set(self._mem) - set(self._pids):
            with contextlib.suppress(OSError):
                os.close(self._mem.pop(pid))
        return self._pids

    def _socket_inodes(self) -> set[int]:
        inodes: set[int] = set()
        for pid in self._pids:
            with contextlib.suppress(OSError):
                for fd in os.listdir(f"/proc/{pid}/fd"):
                    with contextlib.suppress(OSError):
                        link = os.readlink(f"/proc/{pid}/fd/{fd}")
                        if link.startswith("socket:["):
                            inodes.add(int(link[8:-1]))
        return inodes

    def sockets_waiting(self) -> int:
        """Bytes waiting in the tree's sockets (its sockets' inodes are looked up again only
        when a socket with bytes is not known yet: outside a network namespace of its own, the
        machine's other sockets are in the dump too)."""
        total = 0
        refreshed = False
        connected: set[int] = set()
        for q in self.diag.all():
            if q.kind == "tcp" and q.state == TCP_ESTABLISHED:
                connected.add(q.inode)
            if q.waiting <= 0:
                continue
            if q.inode not in self._inodes and not refreshed:
                self._inodes = self._socket_inodes()
                refreshed = True
            if q.inode in self._inodes:
                total += q.waiting
        self.connected = frozenset(connected)
        return total

    def threads(self) -> dict[int, ThreadState]:
        """Every thread of the tree now (gone ones left out)."""
        out: dict[int, ThreadState] = {}
        untimed: set[int] = set()
        for tid, t in list(self._threads.items()):
            try:
                stat = os.pread(t.stat, 1024, 0)
                sched = os.pread(t.schedstat, 128, 0)
            except OSError:
                t.close()
                del self._threads[tid]
                continue
            if not stat:
                continue
            state = stat[stat.rfind(b")") + 2 : stat.rfind(b")") + 3]
            fields = sched.split()
            runs = int(fields[2]) if len(fields) > 2 else 0
            running = state in (b"R", b"D")  # D: in I/O for the reaction (a write), not done
            polling = False
            if not running and t.role == "node":
                call = self._syscall(t)
                polling = self._short_sleep(t, call)
                if tid == t.pid and _untimed_wait(call):
                    untimed.add(t.pid)
            out[tid] = ThreadState(running, runs, polling, t.role != "infra")
        self.samples += 1
        self.untimed = frozenset(untimed)
        return out

    def long_waits(self) -> list[int]:
        """The package's threads in a timed wait on a condition with more than
        :data:`LONG_WAIT_S` left: a client re-checking on a wall-clock timeout (actionlib's
        ``waitForServer``, 500 ms). Before ``/clock`` starts the bridge lets these end, so that
        they do not end in a tick the machine decides."""
        out = []
        for tid, t in self._threads.items():
            if t.role == "node" and self._timed_wait_left(t) > LONG_WAIT_S:
                out.append(tid)
        return out

    def _timed_wait_left(self, t: _Thread) -> float:
        """Seconds left in a timed futex wait (0 when the thread is in none)."""
        if t.syscall is None:
            return 0.0
        try:
            text = os.pread(t.syscall, 256, 0).split()
        except OSError:
            return 0.0
        if len(text) < 5 or not text[0].isdigit() or int(text[0]) != _FUTEX:
            return 0.0
        op, timeout = int(text[2], 16), int(text[4], 16)
        if not timeout or (op & 127) != _FUTEX_WAIT_BITSET:
            return 0.0
        clock = time.CLOCK_REALTIME if op & _FUTEX_CLOCK_REALTIME else time.CLOCK_MONOTONIC
        left = self._left(t.pid, timeout, absolute=clock)
        return 0.0 if left == float("inf") else left

    @staticmethod
    def _syscall(t: _Thread) -> list[int]:
        """The thread's blocking system call and its arguments ([] where none is shown)."""
        if t.syscall is None:
            return []
        try:
            text = os.pread(t.syscall, 256, 0).split()
        except OSError:
            return []
        if len(text) < 7 or not text[0].isdigit():
            return []
        return [int(text[0]), *(int(a, 16) for a in text[1:7])]

    def _short_sleep(self, t: _Thread, call: list[int]) -> bool:
        if not call:
            return False
        nr, args = call[0], call[1:]
        if nr == _NANOSLEEP:
            return self._left(t.pid, args[0], absolute=None) <= POLL_SLEEP_S
        if nr == _CLOCK_NANOSLEEP:
            clock = args[0] if args[1] & _TIMER_ABSTIME else None
            return self._left(t.pid, args[2], absolute=clock) <= POLL_SLEEP_S
        if nr == _FUTEX and args[3]:
            cmd = args[1] & 127
            if cmd == _FUTEX_WAIT:
                return self._left(t.pid, args[3], absolute=None) <= SHORT_SLEEP_S
            if cmd == _FUTEX_WAIT_BITSET:
                realtime = bool(args[1] & _FUTEX_CLOCK_REALTIME)
                clock = time.CLOCK_REALTIME if realtime else time.CLOCK_MONOTONIC
                return self._left(t.pid, args[3], absolute=clock) <= SHORT_SLEEP_S
        return False

    def _left(self, pid: int, addr: int, absolute: int | None) -> float:
        """Seconds the timespec at ``addr`` leaves (relative, or to its deadline on clock
        ``absolute``); infinity where it cannot be read."""
        fd = self._mem.get(pid)
        if fd is None:
            try:
                fd = self._mem[pid] = os.open(f"/proc/{pid}/mem", os.O_RDONLY)
            except OSError:
                self._mem[pid] = -1
                return float("inf")
        if fd < 0 or not addr:
            return float("inf")
        try:
            sec, nsec = _TIMESPEC.unpack(os.pread(fd, _TIMESPEC.size, addr))
        except (OSError, struct.error, OverflowError):
            return float("inf")
        value = float(sec) + float(nsec) / 1e9
        if absolute is None:
            return value
        return value - time.clock_gettime(absolute)  # pacing only: never reaches a message

    # -- the wait --------------------------------------------------------------------------------

    def wait(self, cap_s: float | None) -> bool:
        """Wait until the tree is idle (True) or ``cap_s`` wall seconds passed (False)."""
        deadline = None if cap_s is None else time.perf_counter() + cap_s
        base: dict[int, ThreadState] | None = None
        while True:
            now = self.threads()
            idle = not any(s.running for s in now.values()) and self.sockets_waiting() == 0
            if not idle:
                base = None
            elif base is None or not _still(base, now):
                base = now
            elif _pollers_cycled(base, now):
                return True
            if deadline is not None and time.perf_counter() > deadline:
                return False
            time.sleep(NAP_S)


def _untimed_wait(call: list[int]) -> bool:
    """A futex wait without a timeout (a join, a condition waited on for good)."""
    if not call or call[0] != _FUTEX or call[4]:
        return False
    return (call[2] & 127) in (_FUTEX_WAIT, _FUTEX_WAIT_BITSET)


def _still(base: dict[int, ThreadState], now: dict[int, ThreadState]) -> bool:
    """No watched thread appeared, and none but the pollers of ``base`` ran since."""
    if any(now[tid].watched for tid in set(now) - set(base)):
        return False
    return all(
        s.polling or not s.watched or now.get(tid, s).runs == s.runs for tid, s in base.items()
    )


def _pollers_cycled(base: dict[int, ThreadState], now: dict[int, ThreadState]) -> bool:
    """Every poller of ``base`` has run since (or is gone)."""
    return all(tid not in now or now[tid].runs > s.runs for tid, s in base.items() if s.polling)
