"""The ROS 1 graph on one CPU under SCHED_RR: threads of one node stop racing each other.

Why: two threads of one node (a tf2 listener's spinner beside the main loop) that run on two
CPUs at once interleave differently from run to run, and so does what the node publishes (the
issue saw a spin stop a tick later and a stored marker move 7 mm). On one CPU, under a policy
that does not preempt a running thread for an equal one, a thread runs until it blocks: the
interleaving follows from the order in which they were woken, which the bridge's pacing makes
the same every run. SCHED_RR (priority 1, the kernel's long round-robin slice) is that policy;
plain SCHED_FIFO livelocked once at start-up in the issue's probes, so not that. Real-time
priority also keeps two CPU hogs beside the run from starving it.

Set from the recorder, which is root outside the sandbox (a sandboxed process may not raise its
own policy): every thread of the run, the bridge's included, found in the run's cgroup
(``tasks``) or, without one, as the bridge's descendants. New threads are picked up before each
tick. Where the machine refuses (not root), the run goes on unpinned, as before.
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

from usar_replay.ros1.quiescence import descendants

__all__ = ["OneCpu"]

PRIORITY = 1


class OneCpu:
    """Pins the threads of one run (its cgroup, or the tree under ``root``) to one CPU under
    SCHED_RR; call :meth:`apply` again to catch new threads."""

    def __init__(self, root: int, cgroup: str | None = None, cpu: int | None = None) -> None:
        self.root = root
        self.tasks = Path(cgroup, "tasks") if cgroup else None
        mine = sorted(os.sched_getaffinity(0))
        self.cpu = mine[-1] if cpu is None else cpu
        self.done: set[int] = set()
        self.refused = ""
        """Why the policy could not be set (empty while it could)."""

    def _tids(self) -> list[int]:
        if self.tasks is not None:
            with contextlib.suppress(OSError, ValueError):
                return [int(t) for t in self.tasks.read_text().split()]
        out: list[int] = []
        for pid in descendants(self.root):
            with contextlib.suppress(OSError):
                out += [int(t) for t in os.listdir(f"/proc/{pid}/task")]
        return out

    def apply(self) -> int:
        """Pin the threads not pinned yet; returns how many were."""
        new = [t for t in self._tids() if t not in self.done]
        for tid in new:
            self.done.add(tid)
            try:
                os.sched_setaffinity(tid, {self.cpu})
                if not self.refused:
                    os.sched_setscheduler(tid, os.SCHED_RR, os.sched_param(PRIORITY))
            except ProcessLookupError:
                continue
            except PermissionError as err:
                self.refused = str(err)
        return len(new)
