"""A node's shutdown lands in the tick it began, whatever the machine's timing.

Why: roscpp's ``ros::shutdown()`` plays out on wall-clock time. It first joins its internal
callback thread, which looks for the shutdown every 100 ms of wall time; only then does it
unregister each topic with the master (XML-RPC) and close its connections, join more threads,
and the process exits. A tick takes a few ms, so a node that calls ``ros::shutdown()`` in tick
T used to be seen unregistering (and the run's end found) some ticks later, how many the
machine's speed decided: two recordings' last ticks differed under load.

What is the same in every recording is the tick in which the shutdown *began*: the node's main
thread stops in a wait without a timeout (roscpp's join of its callback thread) while reacting
to that tick's ``/clock``. So, after the graph went idle in a tick (:mod:`.quiescence`, which
notes such main threads), the bridge asks :meth:`ShutdownWatch.starting` which processes'
main threads entered such a wait in this tick, and :meth:`ShutdownWatch.hold` keeps ``/clock``
where it is until each of them has exited and its parent (roslaunch) has collected it (so
roslaunch has seen the exit and acted on it: a ``required`` node's death stops the launch).
Other signs of a shutdown (a connection closed, a node unregistered, a process exited) are
checked by the bridge too, the master asked only in a tick in which a connection closed.

A false sign (a main thread that waits without a timeout for a thread of its own) costs one
hold of at most :data:`HOLD_CAP_S` of wall time, once: only a main thread *entering* such a
wait is a sign, and a process that did not exit within a hold gives no such sign again.
Nothing here is sampled in a tick without a sign.
"""

from __future__ import annotations

import contextlib
import time
import xmlrpc.client
from collections.abc import Callable, Collection, Iterable
from dataclasses import dataclass, field
from typing import Any

__all__ = ["HOLD_CAP_S", "Hold", "ShutdownWatch", "exited", "node_pids", "reaped"]

HOLD_CAP_S = 5.0
"""Wall seconds a hold waits at most for the processes shutting down to exit (a safety net:
roscpp's shutdown takes some 100-400 ms)."""
REAP_CAP_S = 1.0
"""Wall seconds it waits at most for roslaunch to collect them (it polls every 0.1 s)."""
NAP_S = 0.001


def _state(pid: int) -> str | None:
    """The process's state letter, None once it is gone."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as f:
            raw = f.read()
    except OSError:
        return None
    return raw[raw.rfind(b")") + 2 :][:1].decode()


def exited(pid: int) -> bool:
    """True once ``pid`` has exited (a zombie, or gone)."""
    return _state(pid) in (None, "Z", "X")


def reaped(pid: int) -> bool:
    """True once ``pid`` is gone from the process table (its parent collected it)."""
    return _state(pid) is None


def node_pids(master: Any, caller: str, nodes: Iterable[str]) -> dict[str, int]:
    """node name -> its process id, asked of each node (``getPid`` of its slave API; the
    bridge shares the graph's PID namespace). Nodes that do not answer are left out."""
    out: dict[str, int] = {}
    for node in sorted(nodes):
        with contextlib.suppress(OSError, xmlrpc.client.Error, ValueError, TypeError):
            code, _msg, uri = master.lookupNode(caller, node)
            if code != 1:
                continue
            proxy: Any = xmlrpc.client.ServerProxy(str(uri))
            code, _msg, pid = proxy.getPid(caller)
            if code == 1:
                out[node] = int(pid)
    return out


@dataclass(frozen=True)
class Hold:
    """One hold: the processes it waited for, those that exited, and its wall time."""

    pids: tuple[int, ...]
    exited: tuple[int, ...]
    wall_s: float
    capped: bool


@dataclass
class ShutdownWatch:
    """The package's shutdowns, tick by tick (see the module docstring)."""

    collected_by_launcher: bool = True
    """True under roslaunch (it collects its nodes); False for ``rosrun`` (the bridge does)."""
    hold_cap_s: float = HOLD_CAP_S
    reap_cap_s: float = REAP_CAP_S
    _untimed: frozenset[int] = frozenset()
    holds: list[Hold] = field(default_factory=list)
    """Every hold so far (the bridge's log sums them up)."""
    ignored: set[int] = field(default_factory=set)
    """Processes held for once that did not exit within the cap: their main thread's waits
    are no sign any more (a false sign costs one hold, not one per tick)."""

    def starting(self, untimed: Collection[int]) -> set[int]:
        """The processes whose main thread entered a wait without a timeout since the last
        call (``untimed``: :attr:`.quiescence.Quiescence.untimed` after this tick)."""
        new = set(untimed) - self._untimed - self.ignored
        self._untimed = frozenset(untimed)
        return new

    def hold(self, pids: Collection[int], poll: Callable[[], object] = lambda: None) -> Hold:
        """Wait until each of ``pids`` has exited and (under roslaunch) been collected, at
        most :attr:`hold_cap_s` + :attr:`reap_cap_s` wall seconds. ``poll`` is called between
        samples (the bridge notes exit statuses of zombies before roslaunch collects them)."""
        start = time.perf_counter()  # pacing only: never reaches a message
        wanted = tuple(sorted(pids))
        capped = not _wait(lambda: all(exited(p) for p in wanted), self.hold_cap_s, poll)
        done = tuple(p for p in wanted if exited(p))
        self.ignored |= set(wanted) - set(done)
        if done and self.collected_by_launcher:
            capped |= not _wait(lambda: all(reaped(p) for p in done), self.reap_cap_s, poll)
        held = Hold(wanted, done, time.perf_counter() - start, capped)
        self.holds.append(held)
        return held

    def summary(self) -> str:
        """``N holds, M ms at most`` for the bridge's log."""
        if not self.holds:
            return "0 shutdown holds"
        longest = max(h.wall_s for h in self.holds) * 1000.0
        capped = sum(h.capped for h in self.holds)
        return f"{len(self.holds)} shutdown holds (longest {longest:.0f} ms, {capped} capped)"


def _wait(done: Callable[[], bool], cap_s: float, poll: Callable[[], object]) -> bool:
    deadline = time.perf_counter() + cap_s
    while True:
        poll()
        if done():
            return True
        if time.perf_counter() > deadline:
            return False
        time.sleep(NAP_S)
