"""The ROS 1 graph on one CPU under SCHED_RR: threads of one node stop racing each other.

Why: two threads of one node (a tf2 listener's spinner beside the main loop) that run on two
CPUs at once interleave differently from run to run, and so does what the node publishes (the
issue saw a spin stop a tick later and a stored marker move 7 mm). On one CPU, under a policy
that does not preempt a running thread for an equal one, a thread runs until it blocks: the
interleaving follows from the order in which they were woken, which the bridge's pacing makes
the same every run. SCHED_RR (priority 1, the kernel's long round-robin slice) is that policy;
plain SCHED_FIFO livelocked once at start-up in the issue's probes, so not that. Real-time
priority also keeps two CPU hogs beside the run from starving it.

Real-time priority stays inside the run's own CPU set (:mod:`usar_replay.sandbox.cpu_sets`):
the graph's CPU is the set's last, no other run is given it, and a node that widens its
affinity only reaches the set's other CPUs. Without a set of its own the graph is only pinned
(no SCHED_RR: it could starve a CPU someone else needs). The policy carries
SCHED_RESET_ON_FORK, so a node's children and new threads start as ordinary ones until the
next tick's :meth:`OneCpu.apply` (an RR parent cannot hand RR on to a fork bomb). A thread the
idle check moved to ``SCHED_IDLE`` (:mod:`.spinners`: it spins with no pausing point) is
pinned but keeps that policy.

Set from the recorder, which is root outside the sandbox (a sandboxed process may not raise its
own policy): every thread of the run, the bridge's included, found in the run's cgroup
(``tasks``) or, without one, as the bridge's descendants. New threads are picked up before each
tick. Where the machine refuses (not root), the run goes on unpinned, as before.

The idle check's watcher (:mod:`.watcher`) gets no real-time priority: on the graph's CPU it
runs only while the graph does not. Where the graph has SCHED_RR, the watcher is pinned there
too: it then samples only once the graph has stopped (no sample races a reaction or takes the
scheduler's lock from it), and the two hand-overs of every wait, bridge to watcher and back,
happen on a CPU that is running instead of one woken from idle (some 40 microseconds each on a
virtual machine). Without real-time priority it is left on the CPUs it started with, where it
cannot take the graph's CPU from it.
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

from usar_replay.ros1.pacing.quiescence import descendants, last_pid

__all__ = ["OneCpu"]

_LOADAVG = "/proc/loadavg"

PRIORITY = 1
_POLICY = os.SCHED_RR | os.SCHED_RESET_ON_FORK
"""SCHED_RR whose processes and threads start as SCHED_OTHER: real-time priority is given by
the recorder, thread by thread, and never inherited (clearing the flag needs CAP_SYS_NICE,
which nothing in the sandbox has)."""


def _spinner(tid: int) -> bool:
    """A thread the idle check moved to ``SCHED_IDLE`` (:mod:`.spinners`: it spins with no
    pausing point; at real-time priority it would hold the graph's CPU): it keeps that."""
    try:
        return os.sched_getscheduler(tid) & ~os.SCHED_RESET_ON_FORK == os.SCHED_IDLE
    except OSError:
        return False


class OneCpu:
    """Pins the threads of one run (its cgroup, or the tree under ``root``) to one CPU under
    SCHED_RR; call :meth:`apply` again to catch new threads."""

    def __init__(
        self,
        root: int,
        cgroup: str | None = None,
        cpu: int | None = None,
        *,
        realtime: bool = True,
        passes_on: bytes = b"",
        spares: bytes = b"",
    ) -> None:
        self.root = root
        self.spares = spares
        """The module (``python -m``) of the process whose threads get no real-time priority:
        the idle check's watcher (:mod:`.watcher`), which must not take the graph's CPU from
        it (pinned to it beside a real-time graph, else left as it is)."""
        self.passes_on = passes_on
        """A word of the command line of the one process whose threads get SCHED_RR without
        the reset flag (the bridge, usar's own code: rospy starts a thread per new connection,
        which must be real-time from birth as before); its pid once found."""
        self._heir: int | None = None
        self.realtime = realtime
        """SCHED_RR too (only inside the run's own CPU set: never on a CPU another run or the
        host needs)."""
        self.tasks = Path(cgroup, "tasks") if cgroup else None
        mine = sorted(os.sched_getaffinity(0))
        self.cpu = mine[-1] if cpu is None else cpu
        self.done: set[int] = set()
        self.refused = "" if realtime else "no CPU set of the run's own"
        """Why the policy could not be set (empty while it could)."""
        self._last_pid: tuple[bytes, int] | None = None
        """The machine's last PID (and the root) when the threads were last listed
        (:meth:`apply`)."""
        self._loadavg: int | None = None
        """``/proc/loadavg``, kept open until :meth:`close`."""

    def _last_pid_now(self) -> bytes | None:
        """The PID namespace's last PID (:func:`.quiescence.last_pid`); None where unreadable."""
        if self._loadavg is None:
            try:
                self._loadavg = os.open(_LOADAVG, os.O_RDONLY | os.O_CLOEXEC)
            except OSError:
                return None
        return last_pid(self._loadavg)

    def close(self) -> None:
        """Close what :meth:`apply` keeps open."""
        if self._loadavg is not None:
            with contextlib.suppress(OSError):
                os.close(self._loadavg)
            self._loadavg = None

    def _tids(self) -> list[int]:
        if self.tasks is not None:
            with contextlib.suppress(OSError, ValueError):
                return [int(t) for t in self.tasks.read_text().split()]
        out: list[int] = []
        for pid in descendants(self.root):
            with contextlib.suppress(OSError):
                out += [int(t) for t in os.listdir(f"/proc/{pid}/task")]
        return out

    def _policy(self, tid: int) -> int | None:
        """RR with the reset flag, plain RR for the threads of the process named by
        :attr:`passes_on`, None (no real-time priority) for those of the one named by
        :attr:`spares`."""
        if not self.passes_on and not self.spares:
            return _POLICY
        with contextlib.suppress(OSError, ValueError):
            status = Path(f"/proc/{tid}/status").read_text()
            tgid = int(status.split("\nTgid:", 1)[1].split()[0])
            argv = Path(f"/proc/{tgid}/cmdline").read_bytes().split(b"\0")
            if self.spares and argv[1:3] == [b"-m", self.spares]:
                return None
            # python -m ... (not bwrap's argv); the first such process, started before the graph
            if self._heir is None and self.passes_on and argv[1:3] == [b"-m", self.passes_on]:
                self._heir = tgid
            if tgid == self._heir:
                return os.SCHED_RR
        return _POLICY

    def apply(self) -> int:
        """Pin the threads not pinned yet; returns how many were.

        The run's threads are listed again only when a process or thread was made anywhere
        on the machine since the last time (``/proc/loadavg``'s last PID moved: a new thread
        of the run takes a PID in every PID namespace above its own, this one's included).
        Listing them every tick was a fifth of a millisecond of the recorder's own turn (a
        cgroup's ``tasks`` file is built anew on every read), and most ticks make none."""
        now = self._last_pid_now()
        last = None if now is None else (now, self.root)
        if last is not None and last == self._last_pid:
            return 0
        self._last_pid = last
        new = sorted(t for t in self._tids() if t not in self.done)
        for tid in new:
            self.done.add(tid)
            policy = self._policy(tid)
            if policy is None:
                if self.realtime and not self.refused:  # below the graph, on its CPU
                    with contextlib.suppress(OSError):
                        os.sched_setaffinity(tid, {self.cpu})
                continue
            try:
                os.sched_setaffinity(tid, {self.cpu})
                if not self.refused and not _spinner(tid):
                    os.sched_setscheduler(tid, policy, os.sched_param(PRIORITY))
            except ProcessLookupError:
                continue
            except PermissionError as err:
                self.refused = str(err)
        return len(new)
