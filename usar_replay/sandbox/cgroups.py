"""cgroups of either version behind one face: a run's process, memory and CPU groups, made,
read and removed the same way whichever the machine mounts.

Why one face: the kernel sandbox (:mod:`.kernel_sandbox`), the CPU sets (:mod:`.cpu_sets`) and
``usar doctor`` ask the same questions (can a run have a pids, memory, cpuset cgroup here? make
one; remove it) and must get the same answers. Which backend answers is decided once, at the
first question, from the mount: ``/sys/fs/cgroup/cgroup.controllers`` exists only where
``/sys/fs/cgroup`` is the unified v2 hierarchy (:mod:`.cgroup_v2`: one cgroup per run, below a
subtree delegated to usar); otherwise it is v1 (:mod:`.cgroup_v1`: one cgroup per hierarchy,
the machines this project was first measured on). A v1-hybrid machine (v1 controllers plus an
empty v2 tree at ``/sys/fs/cgroup/unified``) is v1.
"""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass

from usar_replay.sandbox import cgroup_v1, cgroup_v2

__all__ = [
    "CONTROLLERS",
    "Support",
    "cpu_root",
    "new_run",
    "remove",
    "run_groups",
    "set_run_limits",
    "support",
    "version",
]

CONTROLLERS = ("memory", "pids", "cpuset")
"""What a run's isolation needs of the cgroups, in the order ``usar doctor`` names them."""


@functools.cache
def version() -> int:
    """2 where ``/sys/fs/cgroup`` is the unified hierarchy, else 1 (decided once a process)."""
    return 2 if os.path.exists(os.path.join(cgroup_v2.MOUNT, "cgroup.controllers")) else 1


@dataclass(frozen=True, slots=True)
class Support:
    """What this machine's cgroups give a run (``usar doctor``'s cgroups line)."""

    version: int
    writable: tuple[str, ...]
    """Which of :data:`CONTROLLERS` a run's cgroup gets."""
    where: str = ""
    """Where the runs' cgroups are made (v2: the delegated subtree and how it was had)."""
    why: str = ""
    """Why not all of them (v2: the kernel's or systemd's answer)."""
    user_manager: bool = False
    """v2 through a user's own systemd manager (whose delegation a drop-in widens)."""


def support() -> Support:
    """What a run's cgroups get here, asked of the same functions a run uses."""
    if version() == 1:
        writable = tuple(c for c in CONTROLLERS if cgroup_v1.writable(c))
        return Support(1, writable, "each controller's own hierarchy")
    got = cgroup_v2.subtree()
    writable = tuple(c for c in CONTROLLERS if c in got.enabled)
    return Support(2, writable, got.how, got.why, got.user_manager)


def run_groups(
    name: str, *, processes: int, memory_mb: int, cpuset: str | None = None
) -> tuple[str | None, str | None]:
    """(pids cgroup, memory cgroup) made for one run named ``name``: the pids one with
    ``processes`` as its limit (None when ``processes`` is 0 or none can be made), the memory
    one limited to ``memory_mb`` MiB (0: counted, not limited; None where none can be made).
    In v2 both are one cgroup: ``cpuset`` (the run's CPU set, already a cgroup of the run) when
    given, else a new one."""
    if version() == 1:
        pids = cgroup_v1.make_pids(name, processes) if processes else None
        return pids, cgroup_v1.make_memory(name, memory_mb)
    on = cgroup_v2.enabled()
    if not processes and "memory" not in on and cpuset is None:
        return None, None
    path = cpuset
    if path is None:
        path = cgroup_v2.make_run(name, processes=processes, memory_mb=memory_mb)
    elif not set_run_limits(path, processes=processes, memory_mb=memory_mb):
        return None, None
    if path is None:
        return None, None
    return (path if processes and "pids" in on else None), (path if "memory" in on else None)


def set_run_limits(path: str, *, processes: int, memory_mb: int) -> bool:
    """v2: write a run's limits in its cgroup ``path`` (made by :func:`cpu_sets.claim`);
    False where the kernel refused one."""
    try:
        cgroup_v2.set_limits(path, processes=processes, memory_mb=memory_mb)
    except OSError:
        return False
    return True


def new_run(name: str, cpus: tuple[int, ...]) -> str | None:
    """A run's cgroup holding ``cpus`` (v2: below the delegated subtree; v1 CPU sets are made
    by :mod:`.cpu_sets` in the cpuset hierarchy)."""
    return cgroup_v2.make_run(name, cpus=cpus) if version() == 2 else None


def cpu_root() -> tuple[str, str] | None:
    """(CPU list, memory nodes) runs' CPU sets are carved from, as the kernel writes them;
    None where this machine gives usar no cpuset cgroup to write."""
    if version() == 2:
        return cgroup_v2.cpu_root()
    root = cgroup_v1.CPUSET_ROOT
    try:
        with open(os.path.join(root, "cpuset.effective_cpus")) as f:
            cpus = f.read()
        with open(os.path.join(root, "cpuset.effective_mems")) as f:
            mems = f.read().strip()
    except OSError:
        return None
    if not os.access(root, os.W_OK):
        return None
    return cpus, mems


def remove(path: str) -> None:
    """Remove one of a run's cgroups, ending whatever of the run is left in it first."""
    if version() == 2:
        cgroup_v2.remove(path)
    else:
        cgroup_v1.remove(path)
