"""Keeping a graded mission to its own files: an audit-hook guard installed in the mission process.

Why: in a class batch (:mod:`usar_replay.batch.plan`) every team's code runs on the same machine as
every other team's logs and submissions. A mission needs to read its own submission folder and
the installed Python packages, and to write scratch files in its working directory; it never
needs another team's files, a subprocess, a socket or a C library loaded by hand. The guard
(:func:`install`, from the mission process before the user's code is imported) refuses those at
the Python level with a :class:`PermissionError` that says why, so a team that tries gets a
failed read (or, uncaught, a ``crashed`` verdict whose traceback names the refusal).

What it is not: a security boundary. Python's audit hooks see what Python code does; a C
extension, a bug in the interpreter or code that rebuilds a module the guard patched (dropping it
from ``sys.modules`` and loading the shared library again by hand, or walking memory with
ctypes objects it already holds) does not pass through them, and nothing inside one process can
stop code in that process from undoing what was done to it. The boundary is the kernel sandbox
(:mod:`usar_replay.sandbox.kernel_sandbox`), which every mission runs in by default; this guard is
the second layer: it turns honest mistakes and casual snooping into a clear ``PermissionError``.

What it closes besides plain ``open``: paths relative to a directory descriptor (``dir_fd=``:
the audit event carries no descriptor, so the guard cannot tell where such a path points and
refuses it); ``/proc`` except the process's own entries (never ``/proc/<other pid>`` nor its own
``mem``); ``_posixsubprocess.fork_exec`` and ``signal.pidfd_send_signal`` (no audit event:
replaced by refusals, and loading ``_posixsubprocess`` again is refused); ``ctypes`` symbol
lookup, calls and memory reads; ``gc`` walks (which find the replaced functions); replacing a
function's ``__code__``; new sockets and ``sendto``. The hook keeps its own copies of these
tables, so changing this module's globals changes nothing.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

__all__ = ["GuardPolicy", "GuardViolation"]

_WRITE_FLAGS = os.O_WRONLY | os.O_RDWR | os.O_CREAT | os.O_TRUNC | os.O_APPEND
_DEVICES = ("/dev/null", "/dev/zero", "/dev/urandom", "/dev/random")
_PROCESS_EVENTS = frozenset(
    {
        "subprocess.Popen",
        "signal.pthread_kill",
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
_NETWORK_EVENTS = frozenset(
    {
        "socket.__new__",
        "socket.connect",
        "socket.bind",
        "socket.getaddrinfo",
        "socket.sendto",
        "socket.sendmsg",
    }
)
_NATIVE_EVENTS = frozenset(
    {
        "ctypes.dlopen",
        "ctypes.dlsym",
        "ctypes.dlsym/handle",
        "ctypes.addressof",
        "ctypes.cdata",
        "ctypes.cdata/buffer",
        "ctypes.call_function",
        "ctypes.string_at",
        "ctypes.wstring_at",
        "ctypes.PyObj_FromPtr",
        "gc.get_objects",
        "gc.get_referrers",
        "gc.get_referents",
    }
)
_NO_REIMPORT = frozenset({"_posixsubprocess", "posix", "os"})
"""Modules whose functions the guard replaces: loading them afresh would undo that."""
_DIR_FD_FUNCTIONS = (
    "open", "stat", "lstat", "access", "readlink", "mkdir", "rmdir", "unlink", "remove",
    "rename", "replace", "link", "symlink", "chmod", "chown", "utime", "mkfifo", "mknod",
)  # fmt: skip
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


class GuardViolation(PermissionError):
    """A mission did something its batch run does not allow (raised in the user's code)."""


@dataclass(frozen=True, slots=True)
class GuardPolicy:
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


def install(policy: GuardPolicy) -> None:
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

    # the hook's own copies: a mission that rebinds this module's globals changes nothing
    devices, write_flags, violation = _DEVICES, _WRITE_FLAGS, GuardViolation
    process_events, network_events = _PROCESS_EVENTS, _NETWORK_EVENTS
    native_events, write_events, list_events = _NATIVE_EVENTS, dict(_WRITE_EVENTS), _LIST_EVENTS
    no_reimport, under, real = _NO_REIMPORT, _under, _real
    own_proc = f"/proc/{os.getpid()}"

    def may_read(path: str) -> bool:
        if path in devices:
            return True
        if path == "/proc" or path.startswith("/proc/"):
            # its own /proc entries (libraries read status, maps), never another process's
            # (a parent's memory) nor its own mem
            return under(path, (own_proc,)) and not path.startswith(own_proc + "/mem")
        if under(path, deny_roots) and not under(path, own_roots):
            return False
        return under(path, read_roots) or under(path, own_roots)

    def refuse(what: str) -> None:
        raise violation(f"usar sandbox: the mission may not {what}")

    def hook(event: str, args: tuple[object, ...]) -> None:
        if event == "open":
            path = real(args[0])
            if path is None:
                return
            mode, flags = args[1], args[2]
            writes = (isinstance(mode, str) and any(c in mode for c in "wax+")) or (
                mode is None and isinstance(flags, int) and bool(flags & write_flags)
            )
            if writes:
                if path not in devices and not under(path, write_roots):
                    refuse(f"write {path} (only its working directory)")
            elif not may_read(path):
                refuse(f"read {path} (outside its own submission and working directory)")
        elif event in list_events:
            path = real(args[0] if args else ".")
            if path is not None and not may_read(path):
                refuse(f"look into {path} (outside its own submission and working directory)")
        elif event in write_events:
            for raw in args[: write_events[event]]:
                path = real(raw)
                if path is not None and not under(path, write_roots):
                    refuse(f"change {path} (only its working directory)")
        elif event in process_events:
            refuse(f"start or signal processes ({event})")
        elif event in network_events:
            refuse(f"use the network ({event})")
        elif event in native_events:
            refuse(f"load or poke native code by hand ({event})")
        elif event == "import" and args and args[0] in no_reimport:
            refuse(f"load {args[0]} again (the guard changed it)")
        elif event == "object.__setattr__" and len(args) > 1 and args[1] == "__code__":
            refuse("replace a function's code")

    _patch_modules(refuse)
    sys.addaudithook(hook)


def _patch_modules(refuse: Callable[[str], None]) -> None:
    """Replace what has no audit event: ``dir_fd=`` paths (the ``open`` event does not say
    which directory they are relative to), ``_posixsubprocess.fork_exec`` (``multiprocessing``
    and ``subprocess`` start processes through it) and ``signal.pidfd_send_signal``."""
    import shutil
    import signal

    shutil._use_fd_functions = False  # type: ignore[attr-defined]  # rmtree without dir_fd
    for module in (os, sys.modules.get("posix")):
        if module is None:
            continue
        for name in _DIR_FD_FUNCTIONS:
            original = getattr(module, name, None)
            if original is not None:
                setattr(module, name, _no_dir_fd(original, refuse))

    def no_process(*_args: object, **_kwargs: object) -> None:
        refuse("start or signal processes (_posixsubprocess.fork_exec, pidfd)")

    import _posixsubprocess  # loaded now, so that a later import gets the patched module

    setattr(_posixsubprocess, "fork_exec", no_process)  # noqa: B010 - mypy knows its type
    setattr(signal, "pidfd_send_signal", no_process)  # noqa: B010
    if hasattr(os, "pidfd_open"):
        setattr(os, "pidfd_open", no_process)  # noqa: B010


def _no_dir_fd(original: Callable[..., Any], refuse: Callable[[str], None]) -> Callable[..., Any]:
    name = getattr(original, "__name__", "os function")

    def checked(*args: Any, **kwargs: Any) -> Any:
        for key in ("dir_fd", "src_dir_fd", "dst_dir_fd"):
            if kwargs.get(key) is not None:
                refuse(f"use a path relative to a directory descriptor (os.{name}, {key}=)")
        return original(*args, **kwargs)

    checked.__name__ = name
    checked.__doc__ = original.__doc__
    return checked
