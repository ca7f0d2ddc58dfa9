"""The kernel sandbox a mission process runs in: bubblewrap (``bwrap``) namespaces and limits.

Why: a mission is untrusted code (a team's, graded against a world it must not see). The
in-process audit guard (:mod:`usar_replay.sandbox.audit_guard`) sees only what Python code does; a C
extension, ``_posixsubprocess`` or ``/proc/<pid>/mem`` walk past it. In its own user, PID,
IPC, UTS, mount, network and cgroup namespaces, as uid 65534 with no capabilities, the process
sees only what is mounted for it: the Python install, the packages, its own submission (all
read-only), a private work dir and a private ``/tmp``. It cannot see, signal or trace any usar
process (its own PID namespace), reach the network (its own network namespace, whose loopback
reaches only itself), or outlive its run (``--die-with-parent``, and the PID namespace ends with
its first process, so a ``setsid`` daemon dies with it).

What bwrap does not do: resource limits. rlimits (address space, CPU time, file size, open
files, no core files) are set by the sandboxed program on itself before any untrusted code runs
(:func:`apply_rlimits`; nothing in the sandbox may raise them again); the process count and
the run's memory are cgroups where they can be made (:mod:`.cgroups`: v1 as root, v2 in a
subtree delegated to usar), else RLIMIT_NPROC (a per-run count in the run's user namespace;
the kernel does not apply it to processes that are root outside, which is why the cgroup comes
first) and RLIMIT_AS per process.

Reusable: :func:`sandbox_argv` builds the command for any program (the ROS 1 bridge runs its graph
with ``network="loopback"``), :class:`KernelSandbox` holds one run's cgroup and limits.
"""

from __future__ import annotations

import contextlib
import functools
import json
import os
import resource
import select
import shutil
import subprocess
import sys
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

from usar_replay.sandbox import cgroups, kernel_pools
from usar_replay.sandbox.cgroup_v1 import TCP_LIMIT_FILE, TCP_PEAK_FILE, tcp_limit_mb
from usar_replay.sandbox.cpu_sets import CpuSet, remove_cgroup
from usar_replay.sandbox.kernel_pools import PoolLimits, succeeds

__all__ = [
    "INSTALL_HINT",
    "TCP_LIMIT_FILE",
    "TCP_PEAK_FILE",
    "KernelSandbox",
    "SandboxLimits",
    "apply_rlimits",
    "bwrap_available",
    "installed",
    "own_tables_argv",
    "own_tables_available",
    "python_binds",
    "sandbox_argv",
    "signal_of_exit",
    "succeeds",
    "tcp_limit_mb",
]

INSTALL_HINT = "apt-get install bubblewrap"
"""How to get bwrap on Debian and Ubuntu (the package ships /usr/bin/bwrap)."""

SANDBOX_UID = 65534
"""``nobody`` inside the sandbox (root outside maps to it; it has no capabilities anywhere)."""

# the operating system's shared libraries and tools a Python process loads; all read-only
_SYSTEM_BINDS = ("/usr", "/bin", "/lib", "/lib32", "/lib64", "/libx32", "/sbin")
_SYSTEM_FILES = ("/etc/ld.so.cache", "/etc/ld.so.conf", "/etc/ld.so.conf.d", "/etc/alternatives")

Network = Literal["none", "loopback"]

_counter = 0
"""Runs made by this process so far (each run's cgroups get a name of their own)."""


@dataclass(frozen=True, slots=True)
class SandboxLimits:
    """What one sandboxed run may use (0: no limit). Past a limit the kernel refuses (a failed
    ``fork``, ``open`` or ``write``: the mission's own error) or kills (memory, CPU time)."""

    memory_mb: int = 4096
    """Address space per process (RLIMIT_AS), MiB."""
    cpu_s: int = 0
    """CPU seconds per process (RLIMIT_CPU; SIGXCPU past it)."""
    processes: int = 256
    """Processes and threads of the run together (a pids cgroup, else RLIMIT_NPROC)."""
    file_mb: int = 1024
    """Largest file a process may write (RLIMIT_FSIZE), MiB."""
    open_files: int = 1024
    """Open file descriptors per process (RLIMIT_NOFILE)."""
    tmp_mb: int = 512
    """Size of the private ``/tmp`` and ``/dev/shm`` (memory-backed file systems), MiB."""
    run_memory_mb: int = 0
    """Memory of the whole run, MiB (0: none): its memory cgroup's ``memory.limit_in_bytes``
    (v1) or ``memory.max`` (v2), which counts every process of the run and the pages of the
    tmpfs mounts it writes (``/tmp``, ``/dev/shm``, a size-limited run folder). Past it the
    kernel's OOM killer ends a process of the run, and the run is ``out_of_memory``."""
    pools: PoolLimits = field(default_factory=PoolLimits)
    """The run's share of the pools the kernel counts per user (inotify, fanotify:
    :mod:`.kernel_pools`)."""


def _bwrap() -> str | None:
    return shutil.which("bwrap")


def installed() -> bool:
    """Whether bwrap is on PATH at all. Why apart from :func:`bwrap_available`: where it is
    installed but cannot make its namespaces (a container's defaults), installing it is no
    advice; what the machine or the container's run lacks is (``usar doctor``)."""
    return _bwrap() is not None


@functools.lru_cache(maxsize=4)
def _probe(bwrap: str) -> tuple[bool, str, bool]:
    """Can ``bwrap`` make the namespaces here? (ok, why not, knows --disable-userns)"""
    argv = [
        bwrap, "--unshare-all", "--unshare-user", "--uid", str(SANDBOX_UID),
        "--gid", str(SANDBOX_UID), "--cap-drop", "ALL", "--die-with-parent", "--new-session",
        "--ro-bind", "/", "/", "--proc", "/proc", "--dev", "/dev", "--", "true",
    ]  # fmt: skip
    try:
        done = subprocess.run(argv, capture_output=True, text=True, timeout=30, check=False)
        helped = subprocess.run(
            [bwrap, "--help"], capture_output=True, text=True, timeout=30, check=False
        )
    except (OSError, subprocess.TimeoutExpired) as err:
        return False, f"{bwrap} could not be run ({err})", False
    if done.returncode != 0:
        said = (done.stderr.strip().splitlines() or [f"exit {done.returncode}"])[-1]
        return False, f"{bwrap} cannot create namespaces here ({said})", False
    return True, "", "--disable-userns" in helped.stdout


def bwrap_available() -> tuple[bool, str]:
    """(True, '') when bwrap is on PATH and can create the sandbox here; else (False, why)."""
    bwrap = _bwrap()
    if bwrap is None:
        return False, "bubblewrap (bwrap) is not installed"
    ok, why, _ = _probe(bwrap)
    return ok, why


def python_binds() -> list[str]:
    """The folders this Python needs, read-only: its install, the venv and usar's package.

    Only ``site``-style folders of ``sys.path`` (under a prefix, or named site-packages /
    dist-packages) are bound, never a development checkout as a whole: a checkout may hold
    recordings and worlds. usar's own package folder is bound by itself."""
    prefixes = {sys.prefix, sys.base_prefix, sys.exec_prefix, sys.base_exec_prefix}
    out = {os.path.realpath(p) for p in prefixes}
    out.add(os.path.dirname(os.path.realpath(sys.executable)))
    for entry in sys.path:
        if not entry or not os.path.isabs(entry) or not os.path.isdir(entry):
            continue
        name = os.path.basename(entry.rstrip(os.sep))
        if name in ("site-packages", "dist-packages"):
            out.add(os.path.realpath(entry))
    out.add(package_dir())
    return sorted(out)


def package_dir() -> str:
    """usar_replay's own folder (bound alone; its parent goes on the sandbox's PYTHONPATH)."""
    return str(Path(__file__).resolve().parents[1])


def _covered(path: str, roots: Iterable[str]) -> bool:
    return any(path == r or path.startswith(r.rstrip("/") + "/") for r in roots)


def sandbox_argv(
    argv: Sequence[str],
    *,
    ro_binds: Sequence[str],
    work_dir: str,
    env: Mapping[str, str],
    limits: SandboxLimits | None = None,
    network: Network = "none",
    hidden: Sequence[str] = (),
    info_fd: int | None = None,
    ro_mounts: Sequence[tuple[str, str]] = (),
    work_at: str = "",
    seccomp_fd: int | None = None,
) -> list[str]:
    """The bwrap command line that runs ``argv`` in the sandbox.

    ``ro_binds``: host paths mounted read-only at the same path (the system's libraries are
    added); ``work_dir``: mounted writable at its own path and the working directory; ``env``:
    the whole environment (bwrap starts from an empty one); ``hidden``: existing files and
    folders (real paths) under a mounted folder that the process must not read (the log being
    written, the grader's files next to the mission's file: /dev/null is mounted over a file,
    an empty read-only tmpfs over a folder; :mod:`usar_replay.sandbox.hide` finds them);
    ``network``: ``none`` and ``loopback`` both give a network namespace of its own, whose
    loopback reaches only processes in the same sandbox (a ROS graph started in it); nothing
    outside is reachable either way. ``info_fd``: where bwrap writes the sandbox's first
    process's host PID (:attr:`KernelSandbox.info_fd`). ``ro_mounts``: (host path, path in the
    sandbox) pairs, each host folder mounted read-only at the other path (a built ROS 1
    workspace at a path that does not depend on the host: :mod:`usar_replay.ros1.building.layout`);
    ``work_at``: where ``work_dir`` appears in the sandbox (default: its own path). Neither
    adds a writable path: ``work_dir`` stays the only one.
    """
    bwrap = _bwrap()
    if bwrap is None:
        raise FileNotFoundError("bwrap")
    _, _, disable_userns = _probe(bwrap)
    lim = limits or SandboxLimits()
    out = [
        bwrap, "--unshare-all", "--unshare-user", "--uid", str(SANDBOX_UID),
        "--gid", str(SANDBOX_UID), "--cap-drop", "ALL", "--die-with-parent", "--new-session",
        "--hostname", "mission", "--clearenv",
    ]  # fmt: skip
    if network not in ("none", "loopback"):
        raise ValueError(f"network={network!r}: expected 'none' or 'loopback'")
    if disable_userns:
        out.append("--disable-userns")  # no nested namespace to regain capabilities in
    if info_fd is not None:
        out += ["--info-fd", str(info_fd)]
    if seccomp_fd is not None:
        out += ["--seccomp", str(seccomp_fd)]
    for path in _SYSTEM_BINDS:
        out += ["--ro-bind-try", path, path]
    for path in _SYSTEM_FILES:
        out += ["--ro-bind-try", path, path]
    # the private file systems first: a bound folder under /tmp (a submission, the work dir)
    # is mounted on top of the private /tmp, not hidden by it
    out += ["--proc", "/proc", "--dev", "/dev"]
    if lim.tmp_mb > 0:
        size = str(lim.tmp_mb * 1024 * 1024)
        out += ["--size", size, "--tmpfs", "/tmp", "--size", size, "--tmpfs", "/dev/shm"]
    else:
        out += ["--tmpfs", "/tmp", "--tmpfs", "/dev/shm"]
    bound: list[str] = []
    for path in sorted(set(ro_binds)):
        if _covered(path, bound) or not os.path.exists(path):
            continue
        out += ["--ro-bind", path, path]
        bound.append(path)
    moved = _checked_mounts(ro_mounts)
    for src, dest in moved:
        out += ["--ro-bind", src, dest]
    visible = [*bound, *_SYSTEM_BINDS, *_SYSTEM_FILES]
    for path in hidden:
        real = os.path.realpath(path)
        inside = [real] if _covered(real, visible) else []
        inside += [dest + real[len(src) :] for src, dest in moved if _covered(real, [src])]
        for seen in inside:  # where the sandbox sees it: its own path, or under a mount
            if os.path.isdir(real):
                # a folder of the grader's inside a mounted one: an empty read-only folder over
                # it (not over a folder that holds a mounted one: that is the mission's own)
                held = (*bound, *(s for s, _ in moved), work_dir)
                if not any(_covered(b, [real]) for b in held):
                    out += ["--perms", "0555", "--tmpfs", seen, "--remount-ro", seen]
            elif os.path.exists(real):
                out += ["--ro-bind", "/dev/null", seen]
    at = work_at or work_dir
    out += ["--bind", work_dir, at, "--chdir", at]
    for key, value in sorted(env.items()):
        out += ["--setenv", key, value]
    return [*out, "--", *argv]


def _checked_mounts(mounts: Sequence[tuple[str, str]]) -> list[tuple[str, str]]:
    """``mounts`` whose host folder exists, each to an absolute, normalised path of its own
    outside the system's folders and the private file systems (a ValueError otherwise: a
    mount over ``/usr`` or ``/proc`` would replace what the sandbox is made of)."""
    out: list[tuple[str, str]] = []
    fixed = ("/proc", "/dev", *_SYSTEM_BINDS, *_SYSTEM_FILES)
    for src, dest in mounts:
        if not os.path.isabs(dest) or os.path.normpath(dest) != dest or dest == "/":
            raise ValueError(f"mount {src} at {dest!r}: expected an absolute, normalised path")
        if _covered(dest, fixed) or any(_covered(f, [dest]) for f in fixed):
            raise ValueError(f"mount {src} at {dest}: that path is the sandbox's own")
        if any(_covered(dest, [d]) or _covered(d, [dest]) for _, d in out):
            raise ValueError(f"mount {src} at {dest}: it overlaps another mount")
        if os.path.exists(src):
            out.append((os.path.realpath(src), dest))
    return out


def signal_of_exit(code: int | None) -> int | None:
    """The signal that ended a sandboxed process, from bwrap's exit status: bwrap itself
    killed gives a negative code; the process inside killed makes bwrap exit 128 + signal."""
    if code is None:
        return None
    if code < 0:
        return -code
    if 128 < code < 128 + 65:
        return code - 128
    return None


def apply_rlimits(limits: Mapping[str, int]) -> None:
    """Set :meth:`KernelSandbox.rlimits` on this process (0: leave that one as it is, except CORE).
    CPU gets a hard limit 5 s above the soft one: SIGXCPU first (a verdict), then SIGKILL."""
    for name, value in limits.items():
        if value <= 0 and name not in ("CORE", "MSGQUEUE"):
            continue
        hard = value + 5 if name == "CPU" else value
        with contextlib.suppress(ValueError, OSError, AttributeError):
            resource.setrlimit(getattr(resource, f"RLIMIT_{name}"), (value, hard))


_OWN_TABLES = (
    "echo 1024 > /proc/sys/net/ipv4/tcp_child_ehash_entries"
    " && echo 256 > /proc/sys/net/ipv4/udp_child_hash_entries"
)
"""Hash tables of their own for the network namespaces created below (Linux 6.1+): 1024 TCP
buckets, ample for a ROS graph's hundred connections; 256 UDP ones, the kernel's least."""


@functools.cache
def own_tables_available() -> bool:
    """Whether :func:`own_tables_argv` can work here (root, ``unshare``, Linux 6.1 or later);
    tried once per process."""
    unshare = shutil.which("unshare")
    if os.geteuid() != 0 or unshare is None:
        return False
    return succeeds([unshare, "--net", "/bin/sh", "-c", _OWN_TABLES])


def own_tables_argv(argv: Sequence[str]) -> list[str]:
    """``argv`` (bwrap) started in an empty network namespace whose child namespaces get TCP
    and UDP hash tables of their own, so the sandbox's namespace, created by bwrap, has them;
    ``argv`` itself where that cannot be done here.

    Why: the ROS 1 bridge asks the kernel for the bytes waiting in its graph's sockets on every
    idle check (:mod:`usar_replay.ros1.pacing.sock_diag`), and a socket dump walks the whole
    table of the namespace. A namespace shares the host's table unless its parent's
    ``tcp_child_ehash_entries`` says otherwise, and the host's has 262,144 buckets on a large
    machine: 0.4-0.8 ms a dump, some 40% of a tick; with 1,024 of its own, 0.02 ms. The host's
    settings are not touched: the setting is made in the empty namespace in between, which
    nothing else uses, and it keeps the same process (``exec``), so bwrap's pid is the one
    started. This also keeps one run's dump from walking another's connections."""
    if not own_tables_available():
        return list(argv)
    unshare = shutil.which("unshare") or "unshare"
    script = "{ " + _OWN_TABLES + '; } 2>/dev/null; exec "$@"'  # bwrap runs whatever this says
    return [unshare, "--net", "/bin/sh", "-c", script, "sh", *argv]


class KernelSandbox:
    """One sandboxed run's pids cgroup, rlimits and first process.

    Start bwrap with :meth:`launch` (``sandbox_argv(..., info_fd=box.info_fd)``, the info fd in
    ``pass_fds``), call :meth:`started` right after, have the program inside call
    :func:`apply_rlimits` with :meth:`rlimits`, and :meth:`close` once bwrap has ended."""

    def __init__(self, limits: SandboxLimits | None = None, cpus: CpuSet | None = None) -> None:
        self.limits = limits or SandboxLimits()
        self.cpus = cpus
        """The run's CPU set (:mod:`.cpu_sets`): its processes start in it and cannot leave;
        :meth:`close` gives it back."""
        global _counter
        _counter += 1
        self.cgroup, self.memory_cgroup = cgroups.run_groups(
            f"usar-mission-{os.getpid()}-{_counter}",
            processes=self.limits.processes,
            memory_mb=self.limits.run_memory_mb,
            cpuset=cpus.path if cpus and cgroups.version() == 2 else None,
        )
        """The run's pids cgroup (limited to :attr:`SandboxLimits.processes`; None where none
        can be made here: then RLIMIT_NPROC). In cgroup v2 it is the run's one cgroup: the
        same folder as :attr:`memory_cgroup` and the CPU set's (:mod:`.cgroups`)."""
        """The run's memory cgroup (limited to :attr:`SandboxLimits.run_memory_mb`): where the
        kernel counts the run's processes it killed for memory (:meth:`oom_killed`); None when
        none can be made here (then RLIMIT_AS per process is the only memory limit)."""
        self._info_r, self.info_fd = os.pipe()
        """Pass to :func:`sandbox_argv` and ``Popen(pass_fds=...)``, then call :meth:`started`."""
        self.seccomp_fd = kernel_pools.keyring_filter_fd()
        """The seccomp filter that refuses keys (None where libseccomp is missing): pass it to
        :func:`sandbox_argv` and ``Popen(pass_fds=...)`` as :attr:`info_fd` (:attr:`fds`)."""
        self._pidfd: int | None = None
        self._counters: dict[tuple[str, bytes], int] = {}
        """The cgroup files :meth:`_counter` keeps open, by (cgroup, key)."""

    @property
    def fds(self) -> tuple[int, ...]:
        """The descriptors bwrap reads (``Popen(pass_fds=...)``): the info fd and the filter."""
        return tuple(fd for fd in (self.info_fd, self.seccomp_fd) if fd is not None and fd >= 0)

    def started(self) -> None:
        """After bwrap was started: hold a pidfd of the sandbox's first process, so that
        :meth:`close` can wait for the PID namespace to end (bwrap's own process exits as soon
        as the program does, while the kernel is still ending the rest of the namespace)."""
        self._close_info(write_end_only=True)
        data = b""
        with contextlib.suppress(OSError):
            while not data.rstrip().endswith(b"}"):
                block = os.read(self._info_r, 4096)
                if not block:
                    break
                data += block
        self._close_info()
        with contextlib.suppress(ValueError, KeyError, TypeError, OSError, AttributeError):
            self._pidfd = os.pidfd_open(int(json.loads(data)["child-pid"]))

    def launch(self, argv: Sequence[str]) -> list[str]:
        """``argv`` (the bwrap command) started inside the run's pids cgroup: a shell moves
        itself into the cgroup and becomes bwrap, so every process of the run is counted from
        the first. (No ``preexec_fn``: Python code between fork and exec can deadlock a
        recorder whose renderer runs threads.) Where it can, bwrap starts from a network
        namespace of its own whose children get connection tables of their own
        (:func:`own_tables_argv`), and in a user namespace of its own that bounds the run's
        share of the kernel's per-user pools (:func:`.kernel_pools.pool_limits_argv`)."""
        argv = own_tables_argv(kernel_pools.pool_limits_argv(argv, self.limits.pools))
        cpuset = self.cpus.path if self.cpus else None
        groups = [g for g in (self.cgroup, self.memory_cgroup, cpuset) if g]
        if not groups:
            return list(argv)
        procs = [os.path.join(g, "cgroup.procs") for g in dict.fromkeys(groups)]
        script = "".join(f'echo 0 > "${i}" 2>/dev/null; ' for i in range(len(procs)))
        return ["/bin/sh", "-c", script + f'shift {len(procs) - 1}; exec "$@"', *procs, *argv]

    def oom_killed(self) -> bool:
        """Whether the kernel's out-of-memory killer ended a process of this run (the memory
        cgroup's ``oom_kill`` count: ``memory.events`` in cgroup v2, ``memory.oom_control``
        in v1). Read it before :meth:`close`, which removes the cgroup."""
        if not self.memory_cgroup:
            return False
        return (
            self._counter(self.memory_cgroup, ("memory.events", "memory.oom_control"), b"oom_kill")
            > 0
        )

    def tcp_refused(self) -> bool:
        """Whether the run's TCP socket buffers reached their cgroup v1 limit (their peak,
        :data:`TCP_PEAK_FILE`, at :func:`tcp_limit_mb`). Read it before :meth:`close`."""
        if not self.memory_cgroup:
            return False
        fd = self._counters.get((self.memory_cgroup, b"tcp"))
        if fd is None:
            try:
                path = os.path.join(self.memory_cgroup, TCP_PEAK_FILE)
                fd = os.open(path, os.O_RDONLY | os.O_CLOEXEC)
            except OSError:
                return False
            self._counters[(self.memory_cgroup, b"tcp")] = fd
        try:
            peak = int(os.pread(fd, 64, 0).strip() or b"0")
        except (OSError, ValueError):
            return False
        return peak >= tcp_limit_mb(self.limits.run_memory_mb) * 1024 * 1024

    def processes_refused(self) -> bool:
        """Whether the run's pids cgroup refused a fork or a thread (``pids.events``: the
        ``max`` count): the run reached its process limit. Read it before :meth:`close`."""
        if not self.cgroup:
            return False
        return self._counter(self.cgroup, ("pids.events",), b"max") > 0

    def _counter(self, group: str, names: tuple[str, ...], key: bytes) -> int:
        """The count ``key`` in the first of ``names`` that ``group`` has (0 where none says).
        The file stays open (:attr:`_counters`): the recorder asks after every tick, and a
        read of an open file is a few microseconds where opening it again each time was a
        tenth of a millisecond."""
        fd = self._counters.get((group, key))
        if fd is None:
            for name in names:
                with contextlib.suppress(OSError):
                    fd = os.open(os.path.join(group, name), os.O_RDONLY | os.O_CLOEXEC)
                    break
            if fd is None:
                return 0
            self._counters[(group, key)] = fd
        with contextlib.suppress(OSError, ValueError):
            for line in os.pread(fd, 4096, 0).splitlines():
                label, _, value = line.partition(b" ")
                if label == key:
                    return int(value)
        return 0

    def rlimits(self) -> dict[str, int]:
        """The rlimits the sandboxed program sets on itself before it runs untrusted code
        (:func:`apply_rlimits`); inherited by all it starts, and no process in the sandbox
        may raise them (that needs a capability in the host's namespace)."""
        lim = self.limits
        mib = 1024 * 1024
        return {
            "AS": lim.memory_mb * mib,
            "CPU": lim.cpu_s,
            "FSIZE": lim.file_mb * mib,
            "NOFILE": lim.open_files,
            "NPROC": 0 if self.cgroup else lim.processes,
            "CORE": 0,
            # POSIX message queues are charged to the host user all runs share (root's
            # RLIMIT_MSGQUEUE quota), not to the run: none for a run (ROS uses none; issue 44)
            "MSGQUEUE": 0,
        }

    def _close_info(self, write_end_only: bool = False) -> None:
        ends = ("info_fd", "seccomp_fd") if write_end_only else ("info_fd", "seccomp_fd", "_info_r")
        for name in ends:
            fd = getattr(self, name)
            if fd is not None and fd >= 0:
                with contextlib.suppress(OSError):
                    os.close(fd)
                setattr(self, name, -1)

    def close(self) -> None:
        """Wait for the PID namespace to end, kill whatever of the run is left in its cgroup
        (nothing, normally) and remove the cgroup. Call once the bwrap process has ended."""
        self._close_info()
        for fd in self._counters.values():
            with contextlib.suppress(OSError):
                os.close(fd)
        self._counters.clear()
        if self._pidfd is not None:
            # the namespace's first process ends last: the kernel ends the others first
            select.select([self._pidfd], [], [], 10.0)
            os.close(self._pidfd)
            self._pidfd = None
        for group in (self.cgroup, self.memory_cgroup):
            if group:
                remove_cgroup(group)
        self.cgroup = self.memory_cgroup = None
        if self.cpus is not None:
            self.cpus.release()
            self.cpus = None

    def __enter__(self) -> KernelSandbox:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
