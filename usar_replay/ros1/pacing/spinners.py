"""Threads that spin with no pausing point: after an allowance of their own CPU time with nothing
new to react to, they count as waiting.

Why: students write ``while (client.getState() != SUCCEEDED) {}`` (no spinOnce, no sleep, no log
line) or ``while (ros::ok()) { if (client.getState() == SUCCEEDED) { ...; sleep } }``, while
the action client's own thread takes in the server's result. ``getState()`` is header code in
the student's binary and ``ros::ok()`` reads a flag: nothing there is a pausing point of the
pacing shim (:mod:`.shim`), the thread never blocks, and the idle check (:mod:`.quiescence`)
never found the graph idle: the start gate gave up ("the graph did not go idle"), or every
tick waited for its wall cap (not repeatable). On Gazebo such a loop burns a CPU and works.

What counts as a spinner: a thread of a C++ node of the package (a Python interpreter's are
left out: a rospy callback that computes in pure Python for milliseconds makes no call either,
and busy rospy nodes are not paced), seen runnable (``/proc/.../syscall`` says ``running``) at
every sample of a run, whose voluntary context switches (``status``: it never blocked), read
and write calls (``io``: ``syscr``, ``syscw``: it took nothing in and put nothing out) and page
faults (``stat``: a computation touching new memory faults, a loop polling the same memory does
not) have not moved since the run began. It *spins*, for the idle check, once it has
used :data:`ALLOWANCE_S` of its own CPU time (``schedstat``'s first field; CPU time, never wall
time, so a loaded machine gives it as long) since the last moment anything new reached the
graph: the base sample of :meth:`.Quiescence.wait`, at which every other thread was blocked,
none of them having run since, and then no bytes waiting in any socket. Then it counts as
waiting. When it reacts (it saw the result the callback thread set: it logs, publishes a goal,
sleeps) it blocks or writes, its run ends, and the normal rules apply again.

Why that is deterministic (the spinner's messages cannot depend on the machine's timing): a
thread that makes no call reads only memory, and while every other thread of the graph is
blocked and has not run, and no byte is on its way, nothing writes that memory but the spinner
itself. What it does next is then a function of its own state alone: the same on every machine,
at any speed. If its loop looks at what it waits for within :data:`ALLOWANCE_S` of CPU time
(a ``getState()`` pass takes well under a microsecond), then by the time it counts as waiting
it has seen the graph's current state and, not having reacted, will not react until something
new arrives: the next tick's messages or ``/clock``, which wake other threads (the base is
taken again) and give it a new allowance. Its reaction therefore lands in the wait, and the
tick, in which what it waits for arrived, on every recording. What is not covered: a thread
that computes for longer than the allowance without a call (it is taken for a spinner and its
result lands in a tick its CPU's speed decides), and a loop that counts its own passes (a line
every millionth pass) or reads the wall clock: as repeatable as the machine's speed, like any
dependence on the wall clock.

Scheduling: the graph runs on one CPU under ``SCHED_RR`` (:mod:`.scheduling`), where a thread
runs until it blocks or its 100 ms round-robin slice ends. A spinner never blocks: at real-time
priority it would hold the CPU from the callback thread that sets what it waits for, from the
bridge, and from the idle check's watcher (an ordinary process beside the graph, which then ran
only in the kernel's real-time throttling window). So a spinner is moved to ``SCHED_IDLE`` the
first time it has used its allowance without a pause (:meth:`Spinners.update`, same owner, no
privilege needed; the flag that keeps children from inheriting a policy is kept), for the rest
of the run: every other thread of the graph (real-time) and the watcher then come before it,
so every other thread's reaction runs before it, to its end, as without it; and the recorder's
:class:`.OneCpu` leaves a thread found in ``SCHED_IDLE`` out of real-time priority. (Against
other sessions' processes it keeps a fair share: the graph leads a session of its own, and the
kernel's autogroups share a CPU between sessions whatever the policies inside them.) The
watcher sleeps (wall time, for pacing only) while a spinner's allowance is all a wait still
needs, so that the spinner gets the CPU.

Cost: each of a tick's two waits lasts at least the allowance while a thread spins (2 x 2 ms
of the spinner's CPU time a tick, more in wall time where it shares its CPU; the recorder's
own work is some 5-8 ms a tick).
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Collection, Mapping
from dataclasses import dataclass

__all__ = ["ALLOWANCE_S", "Key", "Spinners", "spin_key"]

ALLOWANCE_S = 0.002
"""CPU seconds a spinner spends with nothing new before it counts as waiting: well above one
pass of any loop that only polls memory (a ``getState()`` pass takes under a microsecond), and
small beside a tick (50 ms of sim time; the recorder's own work is some 5-8 ms a tick)."""
_ANCHOR_NS = 300_000
"""How long to let a spinner run before its first reading that moved (its anchor): short, so
that little of its CPU time goes uncounted."""
_IDLE = os.SCHED_IDLE | os.SCHED_RESET_ON_FORK


Key = tuple[int, int, int, int]
"""What moves when a thread pauses: (voluntary context switches, read calls, write calls,
page faults)."""


def spin_key(status: bytes, io: bytes, stat: bytes) -> Key | None:
    """The :data:`Key` from a thread's ``status``, ``io`` and ``stat`` files; None where one
    lacks its field."""
    try:
        vol = int(status.split(b"voluntary_ctxt_switches:", 1)[1].split(None, 1)[0])
        reads = int(io.split(b"syscr:", 1)[1].split(None, 1)[0])
        writes = int(io.split(b"syscw:", 1)[1].split(None, 1)[0])
        fields = stat[stat.rindex(b")") + 2 :].split()
        faults = int(fields[7]) + int(fields[9])  # minflt, majflt
    except (IndexError, ValueError):
        return None
    return vol, reads, writes, faults


@dataclass(slots=True)
class _Run:
    """One thread's run without a pause (see the module docstring)."""

    key: Key
    start: int
    """Its CPU time (ns) when the run was first seen."""
    anchor: int | None = None
    """Its CPU time at the first reading after :attr:`start` that moved: ``schedstat`` of a
    thread on another CPU lags its truth by up to a scheduler tick, and a reading that moved
    was exact when it was taken, so time counted from it is time it really ran."""
    base: int | None = None
    """Its CPU time at the wait's base sample (None: no base yet)."""
    base_anchor: int | None = None
    """As :attr:`anchor`, after :attr:`base`."""

    def note(self, cpu: int) -> None:
        if self.anchor is None and cpu != self.start:
            self.anchor = cpu
        if self.base is not None and self.base_anchor is None and cpu != self.base:
            self.base_anchor = cpu


class Spinners:
    """The package's threads in a run without a pause, across one :class:`.Quiescence`'s
    samples (see the module docstring)."""

    def __init__(self, allowance_s: float = ALLOWANCE_S) -> None:
        self.allowance_ns = int(allowance_s * 1e9)
        self._runs: dict[int, _Run] = {}
        self.demoted: set[int] = set()
        """Threads moved to ``SCHED_IDLE`` (each once)."""
        self.refused = ""
        """Why a demotion was refused (empty while none was)."""
        self.moved = 0
        """Threads moved to ``SCHED_IDLE`` so far (gone ones included)."""

    def update(
        self, running: Mapping[int, tuple[int, Key | None]]
    ) -> tuple[frozenset[int], bool]:
        """One sample: ``running`` maps each runnable thread of the package to (its CPU time
        in ns, its :func:`spin_key`). Returns the threads whose run without a pause goes back
        to an earlier sample (the candidates: the others began or changed their run now) and
        whether a thread was demoted in this sample."""
        out: set[int] = set()
        demoted = False
        for tid in set(self._runs) - set(running):
            del self._runs[tid]  # it blocked
        for tid, (cpu, key) in running.items():
            run = self._runs.get(tid)
            if key is None or run is None or run.key != key:
                if key is None:
                    self._runs.pop(tid, None)
                else:
                    self._runs[tid] = _Run(key, cpu)
                continue
            run.note(cpu)
            out.add(tid)
            if (
                tid not in self.demoted
                and run.anchor is not None
                and cpu - run.anchor >= self.allowance_ns
            ):
                demoted = self._demote(tid) or demoted
        return frozenset(out), demoted

    def based(self, candidates: Mapping[int, int]) -> None:
        """A new base sample: ``candidates`` (tid -> CPU time) count their allowance from
        here."""
        for tid, cpu in candidates.items():
            run = self._runs.get(tid)
            if run is not None:
                run.base, run.base_anchor = cpu, None

    def short_s(self, candidates: Collection[int], cpu: Mapping[int, int]) -> float:
        """CPU seconds the least-spent of ``candidates`` still needs since the base (0 or less:
        every one has spun its allowance, they count as waiting), a short time where one has
        no reading that moved since the base yet."""
        need = 0
        for tid in candidates:
            run = self._runs.get(tid)
            if run is None or run.base is None or run.base_anchor is None:
                need = max(need, _ANCHOR_NS)  # a first reading that moved, soon
                continue
            need = max(need, self.allowance_ns - (cpu[tid] - run.base_anchor))
        return need / 1e9

    def _demote(self, tid: int) -> bool:
        """``tid`` to ``SCHED_IDLE`` (see the module docstring); whether it was moved."""
        self.demoted.add(tid)
        try:
            os.sched_setscheduler(tid, _IDLE, os.sched_param(0))
        except PermissionError as err:
            self.refused = self.refused or str(err)
            return False
        except OSError:
            return False
        self.moved += 1
        return True

    def forget(self, tids: Collection[int]) -> None:
        """Threads gone."""
        for tid in tids:
            self._runs.pop(tid, None)
            with contextlib.suppress(KeyError):
                self.demoted.remove(tid)
