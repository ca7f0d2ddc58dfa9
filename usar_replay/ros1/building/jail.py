"""A catkin build in the same kernel sandbox and limits as a run, its output through a pipe.

Why: a package's ``CMakeLists.txt`` runs whatever it likes at build time (``execute_process``),
so the build is the team's code as much as its nodes are. It runs as a run does
(:mod:`~usar_replay.sandbox.kernel_sandbox`): uid 65534 with no capabilities, no network, the
system and Debian's ROS read-only, only its own workspace writable, a pids cgroup and rlimits
(address space, CPU seconds per process, file size, open files, no core files) set by ``prlimit``
before catkin starts, and a wall-clock limit. usar reads its output from a pipe and writes nothing
into the workspace: a file the build could replace with a link is never opened by usar.

Past a limit the build is ``build_failed`` with the limit named (:attr:`BuildOutcome.limit`).
"""

from __future__ import annotations

import contextlib
import os
import re
import signal
import subprocess
import threading
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from usar_replay.core.limits import RunLimits
from usar_replay.sandbox import cpu_sets, kernel_sandbox

__all__ = ["BUILD_WALL_S", "BuildLimits", "BuildOutcome", "run_jailed"]

BUILD_WALL_S = RunLimits().build_wall_s
"""The build's default wall-clock limit, seconds."""

_OUTPUT_CAP = 8 * 1024 * 1024
"""Bytes of the build's output usar keeps (the rest is read and dropped)."""


@dataclass(frozen=True, slots=True)
class BuildLimits:
    """What one build may use; a real build of examples/ros1/usar_course takes ~15 s of wall
    time and ~45 s of CPU on 2 cores, well inside these (0: no limit)."""

    wall_s: float = BUILD_WALL_S
    """Wall seconds for the whole build."""
    cpu_s: int = 600
    """CPU seconds per process (a compiler run)."""
    memory_mb: int = 4096
    """Address space per process, MiB (as a run's ``--memory-mb``)."""
    processes: int = 256
    """Processes and threads of the build together."""
    file_mb: int = 1024
    """Largest file the build may write, MiB."""
    run_memory_mb: int = 0
    """Memory of the whole build, MiB, every process of it together (the run's memory cgroup
    limit, ``--run-memory``; 0: none); past it the kernel's OOM killer ends the build."""
    cpus: int = 0
    """CPUs of the build's own CPU set (the run's share, as a batch gives it; 0: as a run
    claims them): the build never runs on CPUs another run holds (issue 44)."""
    folder_mb: int = 2048
    """The workspace's size while it builds, MiB (a tmpfs of
    :data:`~usar_replay.ros1.building.build_folder.BUILD_FOLDER_INODES` files,
    ``--build-folder``; 0: a plain folder): :mod:`.build_folder`."""


@dataclass(frozen=True, slots=True)
class BuildOutcome:
    code: int
    output: str
    limit: str
    """'' or the limit the build went past, as words ("its 900 s wall limit")."""


def _prlimit(limits: Mapping[str, int]) -> list[str]:
    """``prlimit`` options for :meth:`usar_replay.sandbox.kernel_sandbox.KernelSandbox.rlimits`."""
    out = ["/usr/bin/prlimit"]
    for name, value in limits.items():
        if value <= 0 and name != "CORE":
            continue
        hard = value + 5 if name == "CPU" else value
        out.append(f"--{name.lower()}={value}:{hard}")
    return [*out, "--"]


def _reader(stream: object, keep: bytearray) -> threading.Thread:
    def run() -> None:
        read = getattr(stream, "read")  # noqa: B009
        for block in iter(lambda: read(1 << 16), b""):
            room = _OUTPUT_CAP - len(keep)
            if room > 0:
                keep.extend(block[:room])

    t = threading.Thread(target=run, daemon=True)
    t.start()
    return t


_SAID = (
    (
        re.compile(r"Cannot allocate memory|MemoryError|bad_alloc|memory exhausted|out of memory"),
        "memory",
    ),
    (re.compile(r"CPU time limit exceeded|SIGXCPU"), "cpu"),
    (re.compile(r"File size limit exceeded|SIGXFSZ"), "file"),
    (re.compile(r"Resource temporarily unavailable|[Cc]annot fork|fork: retry"), "processes"),
)


def _limit_words(which: str, limits: BuildLimits) -> str:
    return {
        "memory": f"its memory limit ({limits.memory_mb} MiB per process)",
        "cpu": f"its CPU time limit ({limits.cpu_s} s per process)",
        "file": f"its file size limit ({limits.file_mb} MiB)",
        "processes": f"its process limit ({limits.processes} processes)",
    }[which]


def _pids_hit(cgroup: str | None) -> bool:
    """Did the build's pids cgroup refuse a fork? (``pids.events``: ``max N``)"""
    if not cgroup:
        return False
    try:
        text = Path(cgroup, "pids.events").read_text()
    except OSError:
        return False
    return any(line.split()[:1] == ["max"] and line.split()[1] != "0" for line in text.splitlines())


def run_jailed(
    cmd: Sequence[str],
    *,
    workspace: Path,
    ro_binds: Sequence[str],
    env: Mapping[str, str],
    limits: BuildLimits,
    sandbox: bool,
    workspace_at: str = "",
    ro_mounts: Sequence[tuple[str, str]] = (),
) -> BuildOutcome:
    """Run ``cmd`` with ``workspace`` its only writable folder (see the module doc); without
    ``sandbox`` (no bubblewrap, ``USAR_SANDBOX=off``) it runs with the same rlimits only, as a
    mission does then. In the sandbox, ``workspace`` appears at ``workspace_at`` (default: its
    own path) and each ``ro_mounts`` host folder read-only at its other path
    (:mod:`usar_replay.ros1.building.layout`)."""
    # the run's CPU set and memory cgroup for the build too: its configure step is the
    # team's code, and it ran on every CPU (others' held ones too) and past --run-memory
    try:
        cpus = cpu_sets.claim(limits.cpus) if sandbox else None
    except TimeoutError as err:
        return BuildOutcome(1, "", f"its wait for a free CPU ({err})")
    box = kernel_sandbox.KernelSandbox(
        kernel_sandbox.SandboxLimits(
            memory_mb=limits.memory_mb,
            cpu_s=limits.cpu_s,
            processes=limits.processes,
            file_mb=limits.file_mb,
            run_memory_mb=limits.run_memory_mb if sandbox else 0,
        ),
        cpus=cpus,
    )
    argv = [*_prlimit(box.rlimits()), *cmd]
    fds: tuple[int, ...] = ()
    if sandbox:
        argv = kernel_sandbox.sandbox_argv(
            argv,
            ro_binds=ro_binds,
            work_dir=str(workspace),
            env=env,
            limits=box.limits,
            info_fd=box.info_fd,
            ro_mounts=ro_mounts,
            work_at=workspace_at,
            seccomp_fd=box.seccomp_fd,
        )
        fds = box.fds
    argv = box.launch(argv)
    keep = bytearray()
    timed_out = False
    try:
        proc = subprocess.Popen(
            argv,
            cwd=workspace,
            env=dict(env),
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            pass_fds=fds,
            start_new_session=True,
        )
        if sandbox:
            box.started()
        reader = _reader(proc.stdout, keep)
        try:
            code = proc.wait(timeout=limits.wall_s or None)
        except subprocess.TimeoutExpired:
            timed_out = True
            with contextlib.suppress(OSError):
                os.killpg(proc.pid, signal.SIGKILL)
            code = proc.wait()
        reader.join(timeout=10.0)
        pids = _pids_hit(box.cgroup)
        oom = box.oom_killed()
    finally:
        box.close()
    output = bytes(keep).decode("utf-8", errors="replace")
    limit = ""
    if timed_out:
        limit = f"its {limits.wall_s:g} s wall limit"
    elif oom:
        limit = f"its memory limit for all its processes ({limits.run_memory_mb} MiB: --run-memory)"
    elif pids:
        limit = _limit_words("processes", limits)
    elif code != 0:
        limited = {"memory": limits.memory_mb, "cpu": limits.cpu_s, "file": limits.file_mb,
                   "processes": limits.processes}  # fmt: skip
        for pattern, which in _SAID:
            if limited[which] > 0 and pattern.search(output):
                limit = _limit_words(which, limits)
                break
    return BuildOutcome(code, output, limit)
