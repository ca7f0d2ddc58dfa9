"""Keeping a graded mission to its own files: an audit-hook guard installed in the mission process.

Why: in a class batch (:mod:`usar_replay.batch.plan`) every team's code runs on the same machine as
every other team's logs and submissions. A mission needs to read its own submission folder and
the installed Python packages, and to write scratch files in its working directory; it never
needs another team's files, a subprocess, a socket or a C library loaded by hand. The guard
(:func:`install`, from the mission process before the user's code is imported) refuses those at
the Python level with a :class:`PermissionError` that says why, so a team that tries gets a
failed read (or, uncaught, a ``crashed`` verdict whose traceback names the refusal).

What it is not: a security boundary. Python's audit hooks see what Python code does; a C
extension or a bug in the interpreter does not pass through them. For hostile code, run each run
in a container (docs/batch.md shows the command); this guard keeps honest mistakes and casual
snooping out of the grade.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Sequence
from dataclasses import dataclass

__all__ = ["SandboxPolicy", "SandboxViolation"]

_WRITE_FLAGS = os.O_WRONLY | os.O_RDWR | os.O_CREAT | os.O_TRUNC | os.O_APPEND
_DEVICES = ("/dev/null", "/dev/zero", "/dev/urandom", "/dev/random")
_PROCESS_EVENTS = frozenset(
    {
        "subprocess.Popen",
        "os.system",
        "os.exec",
        "os.posix_spawn",
        "os.spawn",
        "os.fork",
        "os.forkpty",
        "os.kill",
        "os.killpg",
        "pty.spawn",
    }
)
_NETWORK_EVENTS = frozenset({"socket.connect", "socket.bind", "socket.getaddrinfo"})
_NATIVE_EVENTS = frozenset({"ctypes.dlopen", "ctypes.dlsym", "ctypes.addressof", "ctypes.cdata"})
_WRITE_EVENTS = {
    # event -> how many leading arguments are paths
    "os.remove": 1,
    "os.rmdir": 1,
    "os.mkdir": 1,
    "os.rename": 2,
    "os.link": 2,
    "os.symlink": 2,
    "os.truncate": 1,
    "os.chmod": 1,
    "os.chown": 1,
    "os.utime": 1,
    "shutil.rmtree": 1,
    "shutil.copyfile": 2,
    "shutil.move": 2,
}
_LIST_EVENTS = frozenset({"os.listdir", "os.scandir", "glob.glob", "os.chdir"})


class SandboxViolation(PermissionError):
    """A mission did something its batch run does not allow (raised in the user's code)."""


@dataclass(frozen=True, slots=True)
class SandboxPolicy:
    """What one mission process may touch. Paths are absolute; the guard resolves symlinks.

    Reading is allowed under ``read_roots`` (plus the interpreter's own prefixes and import
    path, added by :func:`install`) and never under ``deny_roots`` unless the path is also under
    ``own_roots`` (the team's submission and the run's working directory). Writing is allowed
    only under ``write_roots``.
    """

    read_roots: tuple[str, ...] = ()
    write_roots: tuple[str, ...] = ()
    deny_roots: tuple[str, ...] = ()
    own_roots: tuple[str, ...] = ()

    def install(self) -> None:
        """Install the guard in this process (for good: an audit hook cannot be removed)."""
        install(self)


def _real(path: object) -> str | None:
    if isinstance(path, int):
        return None  # an already open descriptor: it was checked when it was opened
    if isinstance(path, bytes):
        path = os.fsdecode(path)
    if not isinstance(path, str | os.PathLike):
        return None
    return os.path.realpath(os.fspath(path))


def _under(path: str, roots: Sequence[str]) -> bool:
    return any(path == r or path.startswith(r.rstrip(os.sep) + os.sep) for r in roots)


def install(policy: SandboxPolicy) -> None:
    """Install an audit hook enforcing ``policy`` in this process (see the module's docstring)."""
    sys.dont_write_bytecode = True  # never write __pycache__ into a submission or the venv
    prefixes = {sys.prefix, sys.base_prefix, sys.exec_prefix, sys.base_exec_prefix}
    path_entries = [p for p in sys.path if p and os.path.isabs(p)]
    # usar's own package: an editable (development) install is not under the prefixes
    package = os.path.dirname(os.path.abspath(__file__))
    roots = (*prefixes, *path_entries, package, *policy.read_roots)
    norm = [os.path.realpath(p) for p in roots]
    read_roots = tuple(sorted(set(norm)))
    write_roots = tuple(os.path.realpath(p) for p in policy.write_roots)
    deny_roots = tuple(os.path.realpath(p) for p in policy.deny_roots)
    own_roots = tuple(os.path.realpath(p) for p in (*policy.own_roots, *policy.write_roots))

    def may_read(path: str) -> bool:
        if path in _DEVICES or path.startswith("/proc/self/"):
            return True
        if _under(path, deny_roots) and not _under(path, own_roots):
            return False
        return _under(path, read_roots) or _under(path, own_roots)

    def refuse(what: str) -> None:
        raise SandboxViolation(f"usar sandbox: the mission may not {what}")

    def hook(event: str, args: tuple[object, ...]) -> None:
        if event == "open":
            path = _real(args[0])
            if path is None:
                return
            mode, flags = args[1], args[2]
            writes = (isinstance(mode, str) and any(c in mode for c in "wax+")) or (
                mode is None and isinstance(flags, int) and bool(flags & _WRITE_FLAGS)
            )
            if writes:
                if path not in _DEVICES and not _under(path, write_roots):
                    refuse(f"write {path} (only its working directory)")
            elif not may_read(path):
                refuse(f"read {path} (outside its own submission and working directory)")
        elif event in _LIST_EVENTS:
            path = _real(args[0] if args else ".")
            if path is not None and not may_read(path):
                refuse(f"look into {path} (outside its own submission and working directory)")
        elif event in _WRITE_EVENTS:
            for raw in args[: _WRITE_EVENTS[event]]:
                path = _real(raw)
                if path is not None and not _under(path, write_roots):
                    refuse(f"change {path} (only its working directory)")
        elif event in _PROCESS_EVENTS:
            refuse(f"start or signal processes ({event})")
        elif event in _NETWORK_EVENTS:
            refuse(f"use the network ({event})")
        elif event in _NATIVE_EVENTS:
            refuse(f"load or poke native code by hand ({event})")

    sys.addaudithook(hook)
