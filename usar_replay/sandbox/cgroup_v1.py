"""cgroup v1 (a hierarchy per controller), the backend :mod:`.cgroups` picks where
``/sys/fs/cgroup`` is not the unified (v2) file system: Debian 12 with v1 mounted, the
developers' machines and CI.

Why its own module: a v1 run has up to three cgroups, one per hierarchy (``pids``, ``memory``,
``cpuset``), each made below usar's own cgroup of that hierarchy; v2 has one (:mod:`.cgroup_v2`).
The memory cgroup also caps the run's TCP socket buffers, which v1 counts apart from its memory
(``memory.kmem.tcp``) and not at all until a limit is set.
"""

from __future__ import annotations

import contextlib
import os
import signal
import time
from collections.abc import Callable
from pathlib import Path

from usar_replay.sandbox.mountinfo import parse as parse_mounts
from usar_replay.sandbox.mountinfo import read as read_mountinfo

__all__ = [
    "CPUSET_ROOT",
    "TCP_LIMIT_FILE",
    "TCP_PEAK_FILE",
    "controller_root",
    "make_memory",
    "make_pids",
    "remove",
    "tcp_limit_mb",
]

MOUNT = "/sys/fs/cgroup"
CPUSET_ROOT = "/sys/fs/cgroup/cpuset"
"""cgroup v1's cpuset hierarchy (the one this project's machines and CI have)."""

TCP_LIMIT_FILE = "memory.kmem.tcp.limit_in_bytes"
TCP_PEAK_FILE = "memory.kmem.tcp.max_usage_in_bytes"
"""The peak of the run's TCP buffers: the kernel lets TCP go past its limit (it charges by
force and only enters memory pressure; ``failcnt`` stays 0 on 6.x, measured), so the peak
reaching the limit is the verdict."""


def _mount_of(controller: str, mountinfo: str) -> tuple[str, str] | None:
    """(mount point, root within the hierarchy) of ``controller``'s v1 mount below
    :data:`MOUNT`, from the text of ``/proc/self/mountinfo``; None where it has none."""
    for m in parse_mounts(mountinfo):
        mine = m.fstype == "cgroup" and controller in m.super_options
        if mine and m.point.startswith(MOUNT + "/"):
            return m.point, m.root
    return None


def controller_root(
    controller: str, proc_cgroup: str | None = None, mountinfo: str | None = None
) -> str | None:
    """The folder of this process's cgroup in ``controller``'s v1 hierarchy, or None
    (``proc_cgroup``, ``mountinfo``: the texts of ``/proc/self/cgroup`` and
    ``/proc/self/mountinfo``, read when not given).

    Why the mount's root: ``/proc/self/cgroup`` names the cgroup from the hierarchy's root (or
    the cgroup namespace's), but a mount may show only a subtree of it. A container sharing the
    host's cgroup namespace (Docker's default on v1, ``--privileged`` included) sees
    ``/docker/<id>`` in ``/proc/self/cgroup`` while its ``/sys/fs/cgroup/memory`` is already
    that folder (mountinfo's root field ``/docker/<id>``), so the folder is the path less the
    root. A machine's own mounts have root ``/``: the path as it is. A cgroup outside the
    mounted subtree has no folder here (None)."""
    if proc_cgroup is None:
        try:
            proc_cgroup = Path("/proc/self/cgroup").read_text()
        except OSError:
            return None
    if mountinfo is None:
        mountinfo = read_mountinfo()
    for line in proc_cgroup.splitlines():
        _, controllers, path = line.split(":", 2)
        if controller not in controllers.split(","):
            continue
        point, root = _mount_of(controller, mountinfo) or (os.path.join(MOUNT, controller), "/")
        root = root.rstrip("/")
        if path != root and not path.startswith(root + "/"):
            return None  # the mount shows another part of the hierarchy than this cgroup's
        below = path[len(root) :].strip("/")
        return os.path.join(point, below) if below else point
    return None


def writable(controller: str) -> bool:
    """Whether usar can make a cgroup in ``controller``'s hierarchy (below its own)."""
    root = controller_root(controller)
    return root is not None and os.access(root, os.W_OK)


def make_pids(name: str, limit: int) -> str | None:
    """A fresh pids cgroup ``name`` with ``pids.max = limit`` (None when none can be made)."""
    root = controller_root("pids")
    if root is None or not os.access(root, os.W_OK):
        return None
    path = os.path.join(root, name)
    try:
        os.mkdir(path)
        Path(path, "pids.max").write_text(str(limit))
    except OSError:
        with contextlib.suppress(OSError):
            os.rmdir(path)
        return None
    return path


def make_memory(name: str, limit_mb: int) -> str | None:
    """A fresh memory cgroup ``name`` limited to ``limit_mb`` MiB (0: no limit), memory plus
    swap and the TCP buffers (:func:`tcp_limit_mb`) too; None when none can be made."""
    root = controller_root("memory")
    if root is None or not os.access(root, os.W_OK):
        return None  # no memory controller of ours: no per-run record
    path = os.path.join(root, name)
    try:
        os.mkdir(path)
    except OSError:
        return None
    if limit_mb > 0:
        # memory, then memory + swap (v1 wants the second no lower than the first)
        for file in ("memory.limit_in_bytes", "memory.memsw.limit_in_bytes"):
            with contextlib.suppress(OSError):
                Path(path, file).write_text(str(limit_mb * 1024 * 1024))
        with contextlib.suppress(OSError):  # TCP buffers are charged only once capped
            Path(path, TCP_LIMIT_FILE).write_text(str(tcp_limit_mb(limit_mb) * 1024 * 1024))
    return path


def tcp_limit_mb(run_memory_mb: int) -> int:
    """The run's TCP socket buffers, MiB, where cgroup v1 counts them apart from its memory
    (``memory.kmem.tcp``, and not at all until a limit is set: a red team held 1.2 GiB of
    loopback buffers under ``--run-memory 700``, in the host's TCP pool every other run's ROS
    graph shares, issue 44): a quarter of the run's memory, at least 64 MiB (a ROS graph's
    loopback traffic holds a few MiB). cgroup v2 counts socket memory in the run's own."""
    return max(64, run_memory_mb // 4)


def kill_members(path: str) -> None:
    """SIGKILL to every process of a cgroup (``cgroup.procs``: either version's file)."""
    with contextlib.suppress(OSError):
        for pid in Path(path, "cgroup.procs").read_text().split():
            with contextlib.suppress(OSError):
                os.kill(int(pid), signal.SIGKILL)


def rmdir_killing(path: str, kill: Callable[[str], None] = kill_members) -> None:
    """``rmdir`` a cgroup, calling ``kill`` on it while it still has members (a cgroup with
    members cannot be removed), for about 2 s at most; gone already is done. Both backends
    remove a run's cgroup this way, each with its own way to kill."""
    for _ in range(200):
        try:
            os.rmdir(path)
            return
        except FileNotFoundError:
            return
        except OSError:
            kill(path)
            time.sleep(0.01)  # the kernel reaps the killed processes


def remove(path: str) -> None:
    """Remove one of a run's cgroups, killing what is left in it first (nothing, normally)."""
    rmdir_killing(path)
