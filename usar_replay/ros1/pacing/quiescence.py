"""Is the ROS 1 graph idle: has it finished reacting to the last ``/clock``?

Why: the bridge paces the clock by the graph (docs/ros1.md, "Pacing"): the next tick starts as
soon as the graph is done with this one, not after a fixed wall-time wait, so a run is as fast
as the graph and the same on a loaded machine as on an idle one. The graph is idle when

1. every thread of its processes (the bridge's own included, but not the process or thread
   asking) is blocked, at two samples with none of the package's or the bridge's threads run
   in between: ``/proc/<pid>/task/<tid>/syscall`` does not say ``running``, and a thread in a
   call that is not a wait is not ``D`` in its ``stat`` (in uninterruptible I/O, writing its
   output to a file, it is still reacting); see :meth:`Quiescence.threads` for the cheap
   reading of a machine with nothing runnable. One sample is enough where it is a snapshot
   (:meth:`Quiescence.confined`): the whole tree real-time on the asking thread's only CPU,
   and the asker never off that CPU while it read (a tree thread that ran would have taken
   the CPU from it: its count of context switches, ``getrusage``, would have moved);
2. no bytes wait in any of its sockets (:mod:`.sock_diag`: a message on its way between two
   nodes is a reaction not finished), asked once the threads look idle;
3. every thread that was in a *short timed sleep* when the graph first looked idle has woken
   and slept again since (its run count in ``/proc/<pid>/task/<tid>/schedstat`` moved), and no
   other thread ran in between. roscpp's sim-time sleeps (``ros::Rate::sleep``,
   ``Duration::sleep``, timers) poll the clock in 1 ms wall-clock naps (under usar the pacing
   shim, :mod:`.shim`, turns the first two into waits on the clock): such a node looks idle
   while it has not yet noticed the new ``/clock``. A short timed sleep is a ``nanosleep``/
   ``clock_nanosleep`` of at most :data:`POLL_SLEEP_S` or a timed futex wait (a ``wait_for`` on
   a condition) with at most :data:`SHORT_SLEEP_S` to go, read from
   ``/proc/<pid>/task/<tid>/syscall`` and the timeout it points to in ``/proc/<pid>/mem``
   (the graph is the bridge's descendants: allowed).

Processes are found as the bridge's descendants (``/proc/<pid>/task/<tid>/children``); files
stay open and are read again with ``pread`` (a sample of some 45 threads costs 0.05-0.3 ms).
The bridge asks through :mod:`.watcher`, a process of its own.
"""

from __future__ import annotations

import contextlib
import os
import platform
import resource
import struct
import threading
import time
from collections.abc import Collection
from dataclasses import dataclass

from usar_replay.ros1.pacing.sock_diag import SockDiag
from usar_replay.ros1.pacing.spinners import Key, Spinners, spin_key

__all__ = [
    "NAP_S",
    "SHORT_SLEEP_S",
    "ChildrenFiles",
    "Quiescence",
    "ThreadState",
    "children_map",
    "descendants",
]

SHORT_SLEEP_S = 0.002
"""A timed wait on a condition with at most this much left counts as a clock poll (roscpp's
sim-time timers wait 1 ms at a time); a longer one is woken by its condition when it matters.
Twice the timers' period, not more: every tf2 listener's thread waits on its queue 10 ms at a
time (``TransformListener::dedicatedListenerThread``), and a wait that found it within this
of its timeout waited for it to wake for nothing (with 5 ms, half of its time)."""
POLL_SLEEP_S = 0.05
"""A plain sleep of at most this much counts as a poll: nothing but time wakes it (roscpp's
sim-time sleeps nap 1 ms, ``ros::Time::waitForValid`` 10 ms until the first ``/clock``)."""
LONG_WAIT_S = 0.15
"""A timed wait with more than this left at start-up is a wall-clock re-check (see
:meth:`Quiescence.long_waits`); roscpp's own spinners wait 100 ms at a time."""
CONFINED_RECHECK = 32
"""Waits between two checks of :meth:`Quiescence.confined` on an unchanged tree (a thread
may widen its CPUs or lose its real-time policy at any time; new threads are checked at
once)."""
SPIN_CAP_S = 0.1
"""The shortest cap of a wait while a spinner spins (:mod:`.spinners`): a wait asked with a
shorter one (the first tick's, 3 ms) would end at its cap before a spinner could spin its
allowance, on some recordings and not on others."""
STARVED_MAX_S = 2.0
"""The most a wait's cap moves on for the asker's own wait for a CPU (:meth:`Quiescence.wait`)."""
NAP_S = 0.0002
"""Wall time between two samples by default (the asking thread sleeps: on the graph's CPU the
graph runs then, and in the graph's own process its other threads get the interpreter's lock);
:mod:`.watcher`, a process of its own, does not pause."""

_NANOSLEEP = 35
_CLOCK_NANOSLEEP = 230
_FUTEX = 202
_FUTEX_WAIT = 0
_FUTEX_WAIT_BITSET = 9
_FUTEX_CLOCK_REALTIME = 256
_TIMER_ABSTIME = 1
_TIMESPEC = struct.Struct("=qq")
_TIMED = frozenset({_NANOSLEEP, _CLOCK_NANOSLEEP, _FUTEX})
"""The calls whose arguments say how long the wait may last (a poll, or a join)."""
_WAITS = frozenset({7, 23, 34, 35, 43, 45, 47, 61, 128, 130, 202, 230, 232, 247, 270, 271, 281,
                    288, 441} if platform.machine() == "x86_64" else ())  # fmt: skip
"""x86-64 calls a thread blocks in only to wait (poll, select, pause, nanosleep, accept,
recvfrom, recvmsg, wait4, rt_sigtimedwait, rt_sigsuspend, futex, clock_nanosleep, epoll_wait,
waitid, pselect6, ppoll, epoll_pwait, accept4, epoll_pwait2): never in uninterruptible I/O.
Elsewhere none: the state letter is read for every blocked thread."""


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
    cpu: int = 0
    """Its CPU time in ns (schedstat's first field)."""
    spin: Key | None = None
    """A runnable package thread's :func:`.spinners.spin_key` (None for any other)."""
    timer: tuple[int, int, int, int] | None = None
    """Beside a spinner moved aside: a package thread blocked in a timed futex wait that is
    no poll, as (the futex's address, read calls, write calls, page faults); None otherwise.
    The same value at two samples with runs between is a thread that woke on its own timeout
    and went back to the same wait without taking anything in or putting anything out (a tf2
    listener's thread, 10 ms of wall time at a time): see :func:`_still`."""


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


@dataclass(frozen=True, slots=True)
class _Poll:
    """A blocked call's timeout: ``value`` seconds (relative, or a deadline on ``clock``), a
    poll while at most ``limit`` of it is left."""

    value: float
    clock: int | None
    limit: float

    def left(self) -> float:
        if self.clock is None:
            return self.value
        return self.value - time.clock_gettime(self.clock)  # pacing only: never in a message

    def now(self) -> bool:
        """A poll now."""
        return self.left() <= self.limit


class _Thread:
    """Open files of one thread, read again with pread."""

    def __init__(self, pid: int, tid: int) -> None:
        base = f"/proc/{pid}/task/{tid}/"
        self.pid = pid
        self.tid = tid
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
        self.last: ThreadState | None = None
        """The last full reading (which holds while the thread is not run again)."""
        self.status: int | None = None
        self.io: int | None = None
        """``status`` and ``io``, opened when the thread is first seen runnable as the
        package's (:meth:`spin_key`)."""
        self.sched = b""
        """``schedstat`` at that reading (the thread ran since when it reads otherwise)."""
        self.poll: _Poll | None = None
        """The timeout of the package thread's wait then, when the wait is a poll or may
        become one."""
        self.untimed = False
        """The package thread's wait then has no timeout."""

    def spin_key(self) -> Key | None:
        """:func:`.spinners.spin_key` now (None where the files cannot be read, and for a
        Python interpreter's thread: see :mod:`.spinners`)."""
        base = f"/proc/{self.pid}/task/{self.tid}/"
        try:
            if os.path.basename(os.readlink(f"/proc/{self.pid}/exe")).startswith("python"):
                return None
            if self.status is None:
                self.status = os.open(base + "status", os.O_RDONLY)
            if self.io is None:
                self.io = os.open(base + "io", os.O_RDONLY)
            status, io = os.pread(self.status, 4096, 0), os.pread(self.io, 512, 0)
            return spin_key(status, io, os.pread(self.stat, 1024, 0))
        except OSError:
            return None

    def close(self) -> None:
        for fd in (self.stat, self.schedstat, self.syscall, self.status, self.io):
            if fd is not None:
                with contextlib.suppress(OSError):
                    os.close(fd)


class Quiescence:
    """Samples one process tree (see the module docstring); one instance per bridge."""

    def __init__(
        self, root: int | None = None, own_tid: int | None = None, own_pid: int | None = None
    ) -> None:
        self.root = os.getpid() if root is None else root
        self.own_tid = own_tid
        """The asking thread, when it is in the tree (left out)."""
        self.own_pid = own_pid
        """The asking process, when it is in the tree (left out: :mod:`.watcher`)."""
        self.diag = SockDiag()
        self._loadavg = os.open("/proc/loadavg", os.O_RDONLY)
        self._last_pid = b""
        self.children = ChildrenFiles()
        """The tree's walk (:meth:`ChildrenFiles.walk` of :attr:`root`), files kept open."""
        self._threads: dict[int, _Thread] = {}
        self._mem: dict[int, int] = {}
        self._pids: list[int] = []
        self._inodes: set[int] = set()
        self.samples = 0
        """Samples taken (for the bridge's log)."""
        self.snapshots = 0
        """Waits that ended on one sample taken as a snapshot (:meth:`confined`)."""
        self._own_sched: tuple[int, int] | None = None
        """The asking thread's id and its ``schedstat``, open (:meth:`_run_delay`)."""
        self.spinners = Spinners()
        """The package's threads in a run without a pause (:mod:`.spinners`)."""
        self.spun = 0
        """Waits that ended with a spinner counted as waiting."""
        self._confined: bool | None = None
        """:meth:`confined`'s last answer (None: ask again)."""
        self._confined_age = 0
        self.untimed: frozenset[int] = frozenset()
        """The package's processes whose main thread was in a wait without a timeout at the
        last sample (:mod:`.shutdown_watch`: roscpp's ``ros::shutdown`` joins its threads so)."""
        self.connected: frozenset[int] = frozenset()
        """The established TCP connections of the namespace at the last sample (a node's
        ``ros::shutdown`` closes its connections: the bridge asks the master then)."""
        self.ignore: frozenset[int] = frozenset()
        """Sockets (inodes) that hold nothing while the tree is sampled: the asker's own
        socket pair (:mod:`.watcher`), whose request was read before the samples began."""

    def close(self) -> None:
        for t in self._threads.values():
            t.close()
        for fd in self._mem.values():
            with contextlib.suppress(OSError):
                os.close(fd)
        self._threads.clear()
        self._mem.clear()
        self.diag.close()
        if self._loadavg >= 0:
            with contextlib.suppress(OSError):
                os.close(self._loadavg)
            self._loadavg = -1
        self.children.close()
        if self._own_sched is not None:
            with contextlib.suppress(OSError):
                os.close(self._own_sched[1])
            self._own_sched = None

    # -- processes, threads, sockets -------------------------------------------------------------

    def refresh(
        self, package: Collection[int] = (), children: dict[int, list[int]] | None = None
    ) -> list[int]:
        """Find the tree's processes and threads again (new nodes, exited ones); ``package``:
        the pids of the package's processes (the nodes); ``children``: a walk of the tree
        just made (:func:`children_map` of the root)."""
        self._pids = [p for p in descendants(self.root, children) if p != self.own_pid]
        self._confined = None
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
                    t = self._threads.get(tid)
                    if t is not None:
                        role = "bridge" if pid == self.root else "infra"
                        role = "node" if pid in package else role
                        if t.role != role:  # read as a thread of its new role from now on
                            t.role, t.last, t.poll, t.untimed = role, None, None, False
        gone = set(self._threads) - seen
        for tid in gone:
            self._threads.pop(tid).close()
        self.spinners.forget(gone)
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
        waiting, self.connected = self.diag.busy(self.ignore)
        if waiting.keys() - self._inodes:
            self._inodes = self._socket_inodes()
        return sum(n for ino, n in waiting.items() if ino in self._inodes)

    def threads(self, confined: bool = False) -> dict[int, ThreadState]:
        """Every thread of the tree now (gone ones left out).

        A thread's ``schedstat`` moves whenever it is given a CPU. When the kernel reports no
        runnable thread on the machine but the one asking (``/proc/loadavg``), a thread whose
        ``schedstat`` has not moved since its last full reading is blocked in the same call as
        then, and that reading stands: an idle graph costs one small read per thread. So it
        does where the tree is ``confined`` (:meth:`confined`: every thread real-time on the
        asker's only CPU, so none can wait for a CPU while the asker runs; whatever runs on
        the other CPUs, the recorder rendering the next tick meanwhile, is not the tree's),
        and once this sample found a thread running (the sample says "not idle" whatever the
        others do; they are read in full again once they have run). Otherwise the
        thread's ``syscall`` file says ``running`` for a thread on or waiting for a CPU, else
        the call it is blocked in; its ``stat`` (the state letter, ``D`` for a thread in
        uninterruptible I/O) is read only for a thread blocked in a call that is not a wait
        (a ``write`` to a file)."""
        out: dict[int, ThreadState] = {}
        untimed: set[int] = set()
        quiet = confined or self._nothing_runnable()
        busy = False  # a thread found running: this sample is no base, the rest may be stale
        for tid, t in list(self._threads.items()):
            try:
                sched = os.pread(t.schedstat, 128, 0)
                last = t.last
                if (quiet or busy) and sched == t.sched and last is not None and not last.running:
                    if t.poll is not None and t.poll.clock is not None:
                        polling = t.poll.now()  # a deadline: nearer now
                        if polling != last.polling:
                            last = t.last = ThreadState(
                                False, last.runs, polling, last.watched, last.cpu
                            )
                    out[tid] = last
                    if t.untimed:
                        untimed.add(t.pid)
                    continue
                t.sched = sched
                fields = sched.split()
                runs = int(fields[2]) if len(fields) > 2 else 0
                cpu = int(fields[0]) if fields else 0
                text = os.pread(t.syscall, 256, 0) if t.syscall is not None else b""
                if not text or not (text[:1].isdigit() or text.startswith(b"running")):
                    text = b""  # no syscall file (or -1: not in a call): the state letter
                    stat = os.pread(t.stat, 1024, 0)
                    running = stat[stat.rfind(b")") + 2 : stat.rfind(b")") + 3] in (b"R", b"D")
            except OSError:
                t.close()
                del self._threads[tid]
                continue
            nr = -1
            if text:
                running = text.startswith(b"running")
                if not running:
                    nr = int(text[: text.find(b" ")])
                    if nr not in _WAITS:  # blocked, but maybe in I/O (D) for the reaction
                        try:
                            stat = os.pread(t.stat, 1024, 0)
                        except OSError:
                            stat = b""
                        running = stat[stat.rfind(b")") + 2 : stat.rfind(b")") + 3] == b"D"
            polling = False
            timer = None
            t.poll, t.untimed = None, False
            if not running and t.role == "node" and nr in _TIMED:
                call = [nr, *(int(a, 16) for a in text.split()[1:7])]
                t.poll = self._poll(t, call)
                t.untimed = tid == t.pid and _untimed_wait(call)
                polling = t.poll is not None and t.poll.now()
                if t.untimed:
                    untimed.add(t.pid)
                if self.spinners.demoted and nr == _FUTEX and call[4] and not polling:
                    timer = _timer(call[1], t.spin_key())
            # a runnable thread of the package: is it in a run without a pause (:mod:`.spinners`)
            spin = t.spin_key() if running and t.role == "node" else None
            out[tid] = t.last = ThreadState(
                running, runs, polling, t.role != "infra", cpu, spin, timer
            )
            busy = busy or running
        self.samples += 1
        self.untimed = frozenset(untimed)
        return out

    def created(self) -> bool:
        """Whether a process or thread was created in the caller's PID namespace since the
        last call (``/proc/loadavg``'s last field, the namespace's last PID, moved; True at the
        first call). In the kernel sandbox the namespace is the run's: when this is False,
        the tree's processes and threads are those of the last walk, or fewer."""
        last = self._last_pid_now()
        if last is None:
            return True
        new = last != self._last_pid
        self._last_pid = last
        return new

    def _last_pid_now(self) -> bytes | None:
        """The PID namespace's last PID (:func:`last_pid`)."""
        return last_pid(self._loadavg)

    def _nothing_runnable(self) -> bool:
        """No thread of the machine runnable but the caller (``/proc/loadavg``'s fourth field
        is ``1/...``)."""
        try:
            load = os.pread(self._loadavg, 128, 0)
        except OSError:
            return False
        return load.split()[3].startswith(b"1/") if load.count(b" ") >= 3 else False

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

    def _poll(self, t: _Thread, call: list[int]) -> _Poll | None:
        """The timeout of ``call`` (a blocking call and its arguments) when the wait is a
        short timed sleep (see the module docstring) or a timed wait that becomes one when it
        has little left; None for any other."""
        nr, args = call[0], call[1:]
        if nr == _NANOSLEEP:
            return _Poll(self._timespec(t.pid, args[0]), None, POLL_SLEEP_S)
        if nr == _CLOCK_NANOSLEEP:
            clock = args[0] if args[1] & _TIMER_ABSTIME else None
            return _Poll(self._timespec(t.pid, args[2]), clock, POLL_SLEEP_S)
        if nr == _FUTEX and args[3]:
            cmd = args[1] & 127
            if cmd == _FUTEX_WAIT:
                return _Poll(self._timespec(t.pid, args[3]), None, SHORT_SLEEP_S)
            if cmd == _FUTEX_WAIT_BITSET:
                realtime = bool(args[1] & _FUTEX_CLOCK_REALTIME)
                clock = time.CLOCK_REALTIME if realtime else time.CLOCK_MONOTONIC
                return _Poll(self._timespec(t.pid, args[3]), clock, SHORT_SLEEP_S)
        return None

    def _left(self, pid: int, addr: int, absolute: int | None) -> float:
        """Seconds the timespec at ``addr`` leaves (relative, or to its deadline on clock
        ``absolute``); infinity where it cannot be read."""
        return _Poll(self._timespec(pid, addr), absolute, 0.0).left()

    def _timespec(self, pid: int, addr: int) -> float:
        """The timespec at ``addr`` in process ``pid``, in seconds; infinity where it cannot
        be read."""
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
        return float(sec) + float(nsec) / 1e9

    def confined(self) -> bool:
        """Whether one sample is a snapshot of the tree: the asking thread may run on one CPU
        only, and every thread of the tree on that CPU only, under a real-time policy (as
        :mod:`.scheduling` sets the graph beside the watcher). There, a tree thread that
        becomes runnable takes the CPU from the asker at once, so a sample during which the
        asker never left its CPU (:meth:`_switches`) saw every thread as it was at one instant,
        and a second sample to show that none ran in between adds nothing. Asked again after
        each change of the tree, and every :data:`CONFINED_RECHECK` waits."""
        self._confined_age += 1
        if self._confined is not None and self._confined_age < CONFINED_RECHECK:
            return self._confined
        self._confined_age = 0
        self._confined = False
        try:
            mine = os.sched_getaffinity(0)
            if len(mine) != 1 or os.sched_getscheduler(0) != os.SCHED_OTHER:
                return False
            for tid in self._threads:
                rr = os.sched_getscheduler(tid) & ~os.SCHED_RESET_ON_FORK
                if rr not in (os.SCHED_RR, os.SCHED_FIFO) or os.sched_getaffinity(tid) != mine:
                    return False
        except OSError:
            return False
        self._confined = bool(self._threads)
        return self._confined

    @staticmethod
    def _switches() -> tuple[int, int]:
        """The asking thread's voluntary and involuntary context switches."""
        use = resource.getrusage(resource.RUSAGE_THREAD)
        return use.ru_nvcsw, use.ru_nivcsw

    # -- the wait --------------------------------------------------------------------------------

    def wait(self, cap_s: float | None, nap_s: float = NAP_S) -> bool:
        """Wait until the tree is idle (True) or ``cap_s`` wall seconds passed (False),
        sampling every ``nap_s`` (0: at once again, for a caller on a CPU of its own).

        A package thread in a run without a pause (:mod:`.spinners`) counts as waiting once
        it has spun its allowance of CPU time since the base (every other thread blocked and
        not run since, the pollers cycled); while that is all the wait needs, the asker sleeps
        for the CPU time still missing (wall time, for pacing only: the spinner needs the CPU
        the asker may share). The cap counts only time the asker could run: its own wait for
        a CPU (``schedstat``'s run delay, beside a real-time spinner not yet moved aside)
        moves the cap on, at most :data:`STARVED_MAX_S` a wait, and so does a spinner moved
        aside in this wait (a fresh cap, once per thread); while a spinner spins the cap is
        at least :data:`SPIN_CAP_S`."""
        began = time.perf_counter()
        deadline = None if cap_s is None else began + cap_s
        delay = self._run_delay()
        moved = 0.0
        base: dict[int, ThreadState] | None = None
        alone = self.confined()
        while True:
            before = self._switches() if alone else None
            now = self.threads(alone)
            spin, demoted = self.spinners.update(
                {tid: (s.cpu, s.spin) for tid, s in now.items() if s.running and s.spin}
            )
            if demoted:
                # no snapshots from here on: a woken SCHED_IDLE thread does not take the CPU
                # from the asker (:meth:`confined`), and its stale reading would stand
                alone, self._confined = False, None
                if cap_s is not None:
                    deadline = time.perf_counter() + cap_s
            short = 0.0
            aside = False  # a thread moved aside is runnable and reacting: let it have the CPU
            others = [tid for tid, s in now.items() if s.running and tid not in spin]
            if others:
                if not (spin and base is not None and _timers(base, others)):
                    base = None  # a thread reacting (one waking on its timer: see :func:`_still`)
                aside = any(now[tid].running for tid in self.spinners.demoted if tid in now)
            elif (
                not spin
                and before is not None
                and self._switches() == before
                and not any(s.polling for s in now.values())
                # no thread made since the tree was found (it would not be in the sample)
                and self._last_pid_now() == self._last_pid
            ):
                # a snapshot: nothing of the tree ran while it was read (see :meth:`confined`)
                if self.sockets_waiting() == 0:
                    self.snapshots += 1
                    return True
                base = None
            elif base is None or not _still(base, now, spin, woke_ok=bool(spin)):
                base = now
                self.spinners.based({tid: now[tid].cpu for tid in spin})
            elif _pollers_cycled(base, now):
                short = self.spinners.short_s(spin, {tid: now[tid].cpu for tid in spin})
                # the sockets last: bytes written while every thread sampled blocked woke a
                # reader (which the thread samples see run); only bytes no thread will read
                # until a timer fires (Nagle's small writes, held for an acknowledgement) are
                # left for this, one dump a wait instead of one a sample
                if short <= 0:
                    if self.sockets_waiting() == 0:
                        self.spun += bool(spin)
                        return True
                    base = None
            if deadline is not None and (clock := time.perf_counter()) > deadline:
                if spin and clock - began < SPIN_CAP_S:
                    deadline = began + SPIN_CAP_S  # a cap shorter than a spinner's allowance
                starved = min(self._run_delay() - delay, STARVED_MAX_S) - moved
                if starved > 0.001:
                    deadline, moved = deadline + starved, moved + starved
                elif clock > deadline:
                    self.sockets_waiting()  # :attr:`connected` as of the wait's end all the same
                    return False
            if short > 0:
                time.sleep(short)  # pacing only: the spinner's CPU time decides
            elif nap_s > 0 or aside or spin:
                # a spinner or a thread moved aside needs the CPU the asker may share: its
                # allowance grows while the asker waits for the rest
                time.sleep(max(nap_s, NAP_S))

    def _run_delay(self) -> float:
        """Seconds the asking thread has waited for a CPU so far (its ``schedstat``'s second
        field, the file kept open; 0 where it cannot be read)."""
        tid = threading.get_native_id()
        try:
            if self._own_sched is None or self._own_sched[0] != tid:
                if self._own_sched is not None:
                    os.close(self._own_sched[1])
                self._own_sched = (tid, os.open("/proc/thread-self/schedstat", os.O_RDONLY))
            return int(os.pread(self._own_sched[1], 128, 0).split()[1]) / 1e9
        except (OSError, IndexError, ValueError):
            return 0.0


def last_pid(loadavg: int) -> bytes | None:
    """The last PID given out in the caller's PID namespace: ``/proc/loadavg``'s last field,
    read from ``loadavg`` (that file, kept open); None where it cannot be read. A new process
    or thread anywhere below the namespace takes a PID in it too, so an unchanged value means
    none was made since."""
    try:
        return os.pread(loadavg, 128, 0).split()[-1]
    except (OSError, IndexError):
        return None


def _untimed_wait(call: list[int]) -> bool:
    """A futex wait without a timeout (a join, a condition waited on for good)."""
    if not call or call[0] != _FUTEX or call[4]:
        return False
    return (call[2] & 127) in (_FUTEX_WAIT, _FUTEX_WAIT_BITSET)


def _timers(base: dict[int, ThreadState], tids: Collection[int]) -> bool:
    """Every one of ``tids`` was in a timed futex wait at ``base`` (:attr:`ThreadState.timer`):
    found running now, it may be waking on its timeout (the next sample tells)."""
    return all(tid in base and base[tid].timer is not None for tid in tids)


def _timer(addr: int, key: Key | None) -> tuple[int, int, int, int] | None:
    """:attr:`ThreadState.timer` of a thread in a timed futex wait on ``addr``."""
    return None if key is None else (addr, key[1], key[2], key[3])


def _still(
    base: dict[int, ThreadState],
    now: dict[int, ThreadState],
    spinning: Collection[int] = (),
    *,
    woke_ok: bool = False,
) -> bool:
    """No watched thread appeared, and none but the pollers of ``base`` ran since, or the
    ``spinning`` threads (:mod:`.spinners`: runnable at ``base`` and in one run without a pause
    since, their run counts moved by preemption only).

    ``woke_ok`` (while a thread spins): a thread that ran since but is back in the same timed
    futex wait having read, written and faulted nothing (:attr:`ThreadState.timer` unchanged)
    woke on its own wall-clock timeout for nothing, and the spinner's allowance goes on. Why
    that keeps the spinner's reaction where it was: what such a thread does is decided by the
    wall clock anyway (nothing of the graph woke it: a thread that signals it runs, and takes
    the base again), and a wake that took something in reads or faults. Without it a tf2
    listener's thread, waking every 10 ms of wall time, took the base again every 10 ms, and on
    a loaded machine a spinner moved aside could not spin its 2 ms of CPU in between: every
    fourth tick of a team busy-waiting after its mission ended at its cap (issue 51). Not
    covered (as a loop counting its passes is not): a spinner that wakes such a wait itself
    (a futex wake moves none of its counters), whose partner then reacts as often as the
    spinner's CPU lets it."""
    if any(now[tid].watched for tid in set(now) - set(base)):
        return False
    for tid, s in base.items():
        if s.running:
            if tid in spinning:
                continue
            return False  # runnable at the base, and it blocked or wrote since
        n = now.get(tid, s)
        if s.polling or not s.watched or n.runs == s.runs:
            continue
        if woke_ok and s.timer is not None and n.timer == s.timer and not n.running:
            continue  # woke on its own timeout, for nothing
        return False
    return True


def _pollers_cycled(base: dict[int, ThreadState], now: dict[int, ThreadState]) -> bool:
    """Every poller of ``base`` has run since (or is gone)."""
    return all(tid not in now or now[tid].runs > s.runs for tid, s in base.items() if s.polling)
