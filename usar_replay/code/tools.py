"""The external tools (doxygen, cppcheck, clang-format, g++, pdftotext, hunspell) run on a
team's files: on a copy, in the kernel sandbox when there is one, with limits, or said missing.

Why: the tools are trusted programs, their input is not. doxygen, cppcheck and clang-format
have had crashes and unbounded loops on crafted input, and a team's ``Doxyfile`` could name
any path. So a tool runs on a copy of the team's files in a fresh folder (the only folder it
may write), in :mod:`usar_replay.sandbox.kernel_sandbox`'s bubblewrap sandbox when it works here
(no network, the system read-only, uid 65534, no capabilities; ``USAR_SANDBOX=off`` turns it
off), always with a wall-clock limit and rlimits set by ``prlimit`` before it starts (address
space, CPU seconds, file size, open files, no core files). Past a limit the run says which: a team's
finding, never a hang. Without the sandbox (no bubblewrap) the copy, the limits and the
timeout still hold, but the tool could read the machine's files and reach the network: docs/
code-rubric.md says so.

A tool that is not installed is one line naming the Debian package (:func:`missing`); the
rubric lines that need it say so instead of scoring.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import subprocess
import tempfile
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

__all__ = [
    "DEBIAN", "OUTPUT_CAP", "Ran", "ToolLimits", "missing", "run_tool", "sandboxed", "write_copy"
]  # fmt: skip

DEBIAN: dict[str, str] = {
    "doxygen": "doxygen",
    "cppcheck": "cppcheck",
    "clang-format": "clang-format",
    "g++": "g++",
    "pdftotext": "poppler-utils",
    "pdfinfo": "poppler-utils",
    "hunspell": "hunspell hunspell-en-us",
}
"""Each tool and the Debian package(s) that bring it."""

OUTPUT_CAP = 4 * 1024 * 1024
"""Bytes of a tool's output kept."""


@dataclass(frozen=True, slots=True)
class ToolLimits:
    wall_s: float = 30.0
    cpu_s: int = 30
    memory_mb: int = 2048
    file_mb: int = 64


@dataclass(frozen=True, slots=True)
class Ran:
    code: int
    output: str
    """stdout, cut at :data:`OUTPUT_CAP` bytes, decoded leniently."""
    errors: str
    limit: str
    """'' or the limit the tool went past, in words."""
    cut: bool = False
    """Its stdout or stderr was longer than :data:`OUTPUT_CAP` (what is kept is cut)."""


def missing(tool: str) -> str:
    """'' when ``tool`` is on the PATH, else one line naming the Debian package to install."""
    if shutil.which(tool):
        return ""
    return f"{tool} is not installed: apt-get install {DEBIAN.get(tool, tool)}"


def sandboxed() -> bool:
    """Does a tool run in the kernel sandbox here (bubblewrap works, ``USAR_SANDBOX`` is not
    ``off``)?"""
    from usar_replay.sandbox import confinement

    return confinement.confined()


def _prlimit(limits: ToolLimits) -> list[str]:
    """``prlimit`` in front of the tool: rlimits set before it starts, by util-linux's program
    (never a ``preexec_fn``, which is unsafe in a process with threads: ``--jobs``)."""
    mb = 1024 * 1024
    return [
        "/usr/bin/prlimit",
        f"--as={limits.memory_mb * mb}",
        f"--cpu={limits.cpu_s}:{limits.cpu_s + 5}",
        f"--fsize={limits.file_mb * mb}",
        "--core=0",
        "--nofile=256",
        "--",
    ]


def write_copy(files: Iterable[tuple[str, str]], dest: Path) -> None:
    """Each (relative path, text) into ``dest`` as a new file: the copy a tool runs on (paths
    that climb out of ``dest`` are skipped)."""
    for rel, text in files:
        target = dest / rel
        if ".." in Path(rel).parts or Path(rel).is_absolute():
            continue
        target.parent.mkdir(parents=True, exist_ok=True)
        fd = os.open(target, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o644)
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)


_ENV = {"PATH": "/usr/bin:/bin", "HOME": "/tmp", "TMPDIR": "/tmp", "LANG": "C.UTF-8"}


def run_tool(
    argv: Sequence[str],
    work: Path,
    limits: ToolLimits | None = None,
    *,
    sandbox: bool | None = None,
    ro_binds: Sequence[str] = (),
) -> Ran:
    """Run ``argv`` in ``work`` (a folder of usar's making holding the copy: the only one the
    tool may write) under ``limits``; its stdout is read from a file outside ``work``;
    ``ro_binds``: folders of usar's the sandbox shows read-only (usar's built messages)."""
    lim = limits or ToolLimits()
    box = sandboxed() if sandbox is None else sandbox
    cmd = [*_prlimit(lim), *argv]
    if box:
        from usar_replay.sandbox import kernel_sandbox

        cmd = kernel_sandbox.sandbox_argv(
            cmd, ro_binds=list(ro_binds), work_dir=str(work), env=_ENV
        )
    with tempfile.TemporaryDirectory(prefix="usar-tool-") as tmp:
        out_path, err_path = Path(tmp, "out"), Path(tmp, "err")
        timed_out = False
        with out_path.open("wb") as out, err_path.open("wb") as err:
            proc = subprocess.Popen(
                cmd,
                cwd=work,
                env=_ENV,
                stdin=subprocess.DEVNULL,
                stdout=out,
                stderr=err,
                start_new_session=True,
            )
            try:
                code = proc.wait(timeout=lim.wall_s)
            except subprocess.TimeoutExpired:
                timed_out = True
                with contextlib.suppress(OSError):
                    os.killpg(proc.pid, signal.SIGKILL)
                code = proc.wait()
        output, cut_out = _read(out_path)
        errors, cut_err = _read(err_path)
    limit = ""
    if timed_out:
        limit = f"its {lim.wall_s:g} s wall limit"
    elif code in (-signal.SIGXCPU, -signal.SIGKILL) or "CPU time limit" in errors:
        limit = f"its CPU limit ({lim.cpu_s} s)"
    elif code == -signal.SIGXFSZ:
        limit = f"its file size limit ({lim.file_mb} MiB)"
    elif code != 0 and ("bad_alloc" in errors or "out of memory" in errors.lower()):
        limit = f"its memory limit ({lim.memory_mb} MiB)"
    return Ran(code, output, errors, limit, cut_out or cut_err)


def _read(path: Path) -> tuple[str, bool]:
    """The first :data:`OUTPUT_CAP` bytes of ``path`` as text, and whether there was more."""
    with path.open("rb") as f:
        data = f.read(OUTPUT_CAP + 1)
    return data[:OUTPUT_CAP].decode("utf-8", "replace"), len(data) > OUTPUT_CAP
