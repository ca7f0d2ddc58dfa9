"""A CPU set per run: each concurrent run owns its CPU(s) through a cpuset cgroup.

Why: a run's log must not depend on who runs beside it. Two runs that share a CPU interleave as
the machine's timing decides, and a ROS 1 graph under real-time priority (:mod:`usar_replay.ros1.
scheduling`) would starve whatever else runs on its CPU. So every run claims CPUs of its own
before it starts: a cpuset cgroup (``/sys/fs/cgroup/cpuset/usar/run-PID-N``, cgroup v1) whose
``cpuset.cpus`` no other usar run holds. The kernel confines every process and thread of the run
to it (``sched_setaffinity`` to other CPUs only narrows to the set's own), and the sandboxed code
cannot write the cgroup's files (the sandbox mounts no ``/sys``; its cgroup namespace shows
``/``). The recorder of the run pins its own threads to the same CPUs (:meth:`CpuSet.pin_caller`):
it and its graph run in lockstep, so they share the set without slowing each other much, and
``--jobs N`` on N CPUs uses N CPUs.

The claim is machine-wide: every usar process takes the lock on the ``usar`` folder
(``flock``), reads the CPUs its live siblings hold, and takes free ones; a set whose owner
process is gone is removed first. With no free CPU the claim waits (a batch never asks for more
sets than there are CPUs: :func:`free_cpus`). Where usar can write no cpuset cgroup (not root
on v1; on v2, a subtree whose manager does not delegate ``cpuset``) :func:`claim` returns None
and the run goes on without a set (docs/batch.md).

cgroup v2 (:mod:`.cgroup_v2`): a run's set is its one cgroup (below usar's delegated subtree,
which differs from one usar process to the next: each has its own systemd scope), so the claims
are recorded apart, in :func:`registry` (``/run/usar/cpu-sets`` as root): a folder per claim
holding its ``cpuset.cpus`` and its cgroup's path, under the same lock and liveness rule.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import shutil
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from usar_replay.sandbox import cgroup_v1, cgroups

__all__ = ["CpuSet", "claim", "free_cpus", "parse_cpus", "remove_cgroup", "want"]

ROOT = cgroup_v1.CPUSET_ROOT
"""cgroup v1's cpuset hierarchy (the one this project's machines and CI have)."""
GROUP = "usar"
"""The folder under :data:`ROOT` that holds every run's set."""
WANT = 2
"""CPUs a run takes when no count is asked for and that many are free: one for the graph, one
for the idle check's watcher process (:mod:`usar_replay.ros1.pacing.watcher`) and the
recorder's simulation, which take turns with the graph."""

WANT_ENV = "USAR_RUN_CPUS"
"""Overrides :data:`WANT` for this process and its children (a whole number from 1). Why: on a
2-CPU machine a run that takes both makes every other usar run wait for its end; with 1, two
runs go side by side (two of a user's terminals, or the test suite's two workers), each on a
CPU of its own. A log's bytes do not depend on it (docs/batch.md, "Isolation")."""


def want() -> int:
    """The CPUs a run takes when no count is asked for: :data:`WANT_ENV`, else :data:`WANT`."""
    text = os.environ.get(WANT_ENV, "").strip()
    return int(text) if text.isdigit() and int(text) > 0 else WANT


_counter = 0


def parse_cpus(text: str) -> list[int]:
    """``0-2,5`` -> [0, 1, 2, 5] (the kernel's list format)."""
    out: list[int] = []
    for part in text.strip().split(","):
        if not part:
            continue
        lo, _, hi = part.partition("-")
        out += range(int(lo), int(hi or lo) + 1)
    return sorted(set(out))


@dataclass(slots=True)
class CpuSet:
    """One run's claimed CPUs and its cpuset cgroup folder."""

    path: str
    cpus: tuple[int, ...]
    record: str = ""
    """cgroup v2: the claim's folder in :func:`registry` (v1: the cgroup is the record)."""
    _saved: dict[int, set[int]] = field(default_factory=dict)

    @property
    def graph_cpu(self) -> int:
        """The CPU a ROS 1 graph runs on under SCHED_RR (the set's last)."""
        return self.cpus[-1]

    @property
    def procs(self) -> str:
        """Write a PID here to move it into the set."""
        return os.path.join(self.path, "cgroup.procs")

    def pin_caller(self) -> None:
        """Pin every thread of this (the recorder's) process to the set; :meth:`release` undoes
        it. Threads started later inherit the creating thread's CPUs."""
        for tid in _threads():
            with contextlib.suppress(OSError):
                self._saved[tid] = os.sched_getaffinity(tid)
                os.sched_setaffinity(tid, self.cpus)

    def release(self) -> None:
        """Give the CPUs back: the recorder's threads as they were, the cgroup removed (the
        sandbox's close has ended its processes; any left are killed)."""
        for tid, cpus in self._saved.items():
            with contextlib.suppress(OSError):
                os.sched_setaffinity(tid, cpus)
        self._saved.clear()
        remove_cgroup(self.path)
        if self.record:
            shutil.rmtree(self.record, ignore_errors=True)


def _threads() -> list[int]:
    try:
        return [int(t) for t in os.listdir("/proc/self/task")]
    except OSError:
        return [0]


def _root_cpus() -> tuple[list[int], str] | None:
    """(CPUs, memory nodes) runs' sets are carved from, or None without a cpuset cgroup to
    write (:func:`.cgroups.cpu_root`)."""
    root = cgroups.cpu_root()
    if root is None:
        return None
    try:
        return parse_cpus(root[0]), root[1]
    except ValueError:
        return None


def registry() -> str:
    """cgroup v2: the folder of the claims (made if missing): ``/run/usar/cpu-sets`` as root,
    else the user's runtime folder's (``$XDG_RUNTIME_DIR``), else one in ``/tmp`` of the user's."""
    if os.geteuid() == 0 and os.access("/run", os.W_OK):
        base = "/run/usar"
    elif os.environ.get("XDG_RUNTIME_DIR"):
        base = os.path.join(os.environ["XDG_RUNTIME_DIR"], "usar")
    else:
        base = f"/tmp/usar-{os.geteuid()}"
    path = os.path.join(base, "cpu-sets")
    os.makedirs(path, mode=0o700, exist_ok=True)
    if os.stat(base).st_uid != os.geteuid():  # another user's folder: not a record of ours
        raise OSError(f"{base} is not this user's")
    return path


def usable_cpus() -> list[int]:
    """The CPUs this process may use that the cpuset root has (empty without a hierarchy)."""
    root = _root_cpus()
    if root is None:
        return []
    return sorted(set(root[0]) & os.sched_getaffinity(0))


@contextlib.contextmanager
def _locked() -> Iterator[str]:
    """The folder of the claims (v1: the ``usar`` cpuset cgroup, made if missing; v2:
    :func:`registry`), held under an exclusive ``flock``."""
    root = _root_cpus()
    if root is None:
        raise OSError("no cpuset cgroup usar can write")
    v1 = cgroups.version() == 1
    group = os.path.join(ROOT, GROUP) if v1 else registry()
    with contextlib.suppress(FileExistsError):
        os.mkdir(group)
    fd = os.open(group, os.O_RDONLY | os.O_DIRECTORY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        cpus, mems = root
        # a new v1 cpuset starts with no CPU and no memory node: give the folder all of them
        if v1 and not Path(group, "cpuset.mems").read_text().strip():
            Path(group, "cpuset.cpus").write_text(",".join(map(str, cpus)))
            Path(group, "cpuset.mems").write_text(mems)
        yield group
    finally:
        os.close(fd)


def _held(group: str) -> set[int]:
    """CPUs held by live runs' sets (the sets of runs whose owner is gone are removed)."""
    out: set[int] = set()
    for name in os.listdir(group):
        path = os.path.join(group, name)
        if not name.startswith("run-") or not os.path.isdir(path):
            continue
        owner = name.split("-")[1]
        if owner.isdigit() and not _alive(int(owner)):
            _forget(path)
            continue
        with contextlib.suppress(OSError, ValueError):
            out |= set(parse_cpus(Path(path, "cpuset.cpus").read_text()))
    return out


def _forget(path: str) -> None:
    """Remove a dead run's claim: its cgroup (v1: ``path`` itself; v2: the one its record
    names) and, in v2, the record."""
    if cgroups.version() == 1:
        remove_cgroup(path)
        return
    with contextlib.suppress(OSError):
        named = Path(path, "cgroup").read_text().strip()
        if named.startswith("/sys/fs/cgroup/"):
            remove_cgroup(named)
    shutil.rmtree(path, ignore_errors=True)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def free_cpus() -> list[int]:
    """The usable CPUs no live usar run holds now (a batch runs at most this many at once)."""
    try:
        with _locked() as group:
            held = _held(group)
    except OSError:
        return usable_cpus()
    return [c for c in usable_cpus() if c not in held]


def claim(count: int = 0, wait_s: float = 600.0) -> CpuSet | None:
    """A set of ``count`` CPUs (0: :func:`want` when free, else 1) no other usar run holds,
    waiting up to ``wait_s`` for one to be given back; None without a cpuset hierarchy here.
    Raises TimeoutError when no CPU came free in time."""
    global _counter
    deadline = time.monotonic() + wait_s
    while True:
        try:
            with _locked() as group:
                free = [c for c in usable_cpus() if c not in _held(group)]
                take = free[: count or want()] if len(free) >= max(count, 1) else []
                if take:
                    _counter += 1
                    return _make(group, f"run-{os.getpid()}-{_counter}", tuple(take))
        except OSError:
            return None
        if time.monotonic() > deadline:
            raise TimeoutError(f"no free CPU for the run within {wait_s:g} s")
        time.sleep(0.2)  # another usar run gives its set back when it ends


def _make(group: str, name: str, take: tuple[int, ...]) -> CpuSet:
    """The set ``name`` of CPUs ``take`` (under the claims' lock): v1 a cpuset cgroup in the
    claims' folder; v2 the run's cgroup below usar's subtree and its record in the registry."""
    if cgroups.version() == 2:
        path = cgroups.new_run(name, take)
        if path is None:
            raise OSError(f"no cgroup for the run's CPU set {name}")
        record = os.path.join(group, name)
        try:
            os.mkdir(record)
            Path(record, "cgroup").write_text(path)
            Path(record, "cpuset.cpus").write_text(",".join(map(str, take)))
        except OSError:
            remove_cgroup(path)
            shutil.rmtree(record, ignore_errors=True)
            raise
        return CpuSet(path, take, record)
    path = os.path.join(group, name)
    os.mkdir(path)
    try:
        Path(path, "cpuset.cpus").write_text(",".join(map(str, take)))
        mems = Path(group, "cpuset.mems").read_text().strip()
        Path(path, "cpuset.mems").write_text(mems)
    except OSError:
        remove_cgroup(path)
        raise
    return CpuSet(path, take)


def remove_cgroup(path: str) -> None:
    """Remove one of a run's cgroups (its CPU set, its memory or pids group), killing what is
    left in it first (nothing, normally): a cgroup with members cannot be removed."""
    cgroups.remove(path)
