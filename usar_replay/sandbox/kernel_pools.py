"""The kernel's per-user pools, bounded per run: inotify and fanotify by a user namespace of
the run's own, keys refused by a seccomp filter.

Why (issue 44): every sandboxed run is the same user outside (bwrap maps its uid 65534 to
usar's own), and the kernel charges some pools to that user, not to a cgroup: inotify
instances and watches, fanotify groups and marks, keys. Without a bound per run, one run takes
what every other run needs: measured here, a sandboxed loop of ``inotify_init()`` took all
128 of the host user's instances, and the next run's first one failed.

- **inotify and fanotify** are counted per user namespace (the kernel's ``ucounts``), and a
  namespace's count is charged to every namespace above it. A user namespace made between
  usar and bwrap, with its own ``/proc/sys/user/max_inotify_instances`` (and watches,
  fanotify groups and marks), bounds what the run below it takes together, however many
  processes or namespaces it makes: it holds no capability there to raise them, and its own
  namespaces are below. The namespace maps root to usar's own user, so files, cgroups and
  bwrap behave as before; it is made with ``unshare`` (util-linux) and keeps the process
  (``exec``), so the PID usar started is bwrap's.
- **Keys** are charged to the host's user itself (``key_user``), in no namespace, so no
  namespace bounds them. A run gets none: bwrap installs a seccomp filter (``--seccomp``) that
  answers ``add_key``, ``request_key`` and ``keyctl`` with EPERM, as Docker's and Flatpak's
  default profiles do; ROS uses no keys. The filter is compiled by libseccomp (Debian's
  ``libseccomp2``, which apt itself depends on), through ctypes: it knows each architecture's
  system call numbers, the 32-bit and x32 ones included, where a hand-written BPF program
  would have to.

POSIX message queues (``RLIMIT_MSGQUEUE`` 0) and SysV IPC (an IPC namespace per run) are
bounded in :mod:`.kernel_sandbox`; pipe and socket buffers are charged to the run's memory
cgroup there.
"""

from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import errno
import functools
import os
import platform
import shutil
import subprocess
from collections.abc import Sequence
from dataclasses import dataclass

__all__ = [
    "PoolLimits",
    "keyring_filter",
    "keyring_filter_fd",
    "pool_limits_argv",
    "pool_limits_available",
    "succeeds",
]

KEY_CALLS = ("add_key", "request_key", "keyctl")
"""The system calls that make or change keys (keyrings): refused in the sandbox."""

_COMPAT_ARCHES = {"x86_64": ("x86", "x32"), "aarch64": ("arm",)}
"""The other ABIs a process of this machine can call the kernel with (libseccomp's names):
a 32-bit program's calls must meet the same filter."""


@dataclass(frozen=True, slots=True)
class PoolLimits:
    """What one run may take of the pools the kernel counts per user namespace (0: no bound
    of the run's own; the host's per-user limit stays). A call past one fails with EMFILE or
    ENOSPC, as on a machine with that limit: the mission's own error."""

    inotify_instances: int = 16
    """inotify instances of the run together (the host user's default is 128 for all runs:
    eight runs at a time get their whole bound). A ROS graph uses none."""
    inotify_watches: int = 8192
    """inotify watches of the run together (each is kernel memory, also charged to the
    run's memory cgroup)."""
    fanotify_groups: int = 16
    """fanotify groups of the run together."""
    fanotify_marks: int = 8192
    """fanotify marks of the run together."""

    def settings(self) -> list[tuple[str, int]]:
        """(``/proc/sys/user`` file, value) for each bound set (a 0 leaves that file)."""
        named = (
            ("max_inotify_instances", self.inotify_instances),
            ("max_inotify_watches", self.inotify_watches),
            ("max_fanotify_groups", self.fanotify_groups),
            ("max_fanotify_marks", self.fanotify_marks),
        )
        return [(name, value) for name, value in named if value > 0]


def _script(limits: PoolLimits) -> str:
    """The shell lines that set the namespace's bounds; a file this kernel lacks (fanotify's
    before Linux 5.13) is skipped, any other failure ends the start (exit 125) rather than
    run unbounded."""
    lines = [
        f"if [ -e /proc/sys/user/{name} ]; then echo {value} > /proc/sys/user/{name} "
        "|| exit 125; fi"
        for name, value in limits.settings()
    ]
    return "; ".join([*lines, 'exec "$@"'])


def succeeds(argv: Sequence[str], timeout_s: float = 10.0) -> bool:
    """Whether ``argv`` runs to exit 0 within ``timeout_s``, its output discarded: the probe
    of what a machine allows (namespaces, settings) before a run relies on it (here, below
    :mod:`.kernel_sandbox`, which uses it too and names it)."""
    try:
        done = subprocess.run(
            argv,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            timeout=timeout_s,
            check=False,
        )
    except (OSError, subprocess.TimeoutExpired):
        return False
    return done.returncode == 0


@functools.cache
def pool_limits_available() -> bool:
    """Whether :func:`pool_limits_argv` can bound a run here (``unshare`` present, user
    namespaces allowed, the inotify bound writable in one); tried once per process."""
    unshare = shutil.which("unshare")
    if unshare is None:
        return False
    probe = "echo 1 > /proc/sys/user/max_inotify_instances"
    return succeeds([unshare, "--user", "--map-root-user", "/bin/sh", "-c", probe])


def pool_limits_argv(argv: Sequence[str], limits: PoolLimits | None = None) -> list[str]:
    """``argv`` (bwrap) started in a user namespace of its own whose per-namespace pools are
    bounded by ``limits``; ``argv`` itself where that cannot be done here
    (:func:`pool_limits_available`, said by ``usar doctor``)."""
    lim = limits or PoolLimits()
    if not lim.settings() or not pool_limits_available():
        return list(argv)
    unshare = shutil.which("unshare") or "unshare"
    return [unshare, "--user", "--map-root-user", "/bin/sh", "-c", _script(lim), "sh", *argv]


@functools.cache
def keyring_filter() -> bytes | None:
    """The seccomp filter (classic BPF, as bwrap's ``--seccomp`` reads it) that allows every
    call but :data:`KEY_CALLS`, refused with EPERM on this machine's ABIs; None where
    libseccomp is missing or does not know this architecture."""
    name = ctypes.util.find_library("seccomp")
    if name is None:
        return None
    try:
        lib = ctypes.CDLL(name, use_errno=True)
    except OSError:
        return None
    lib.seccomp_init.restype = ctypes.c_void_p
    lib.seccomp_init.argtypes = [ctypes.c_uint32]
    lib.seccomp_release.argtypes = [ctypes.c_void_p]
    lib.seccomp_arch_resolve_name.restype = ctypes.c_uint32
    lib.seccomp_arch_resolve_name.argtypes = [ctypes.c_char_p]
    lib.seccomp_arch_add.argtypes = [ctypes.c_void_p, ctypes.c_uint32]
    lib.seccomp_syscall_resolve_name.argtypes = [ctypes.c_char_p]
    lib.seccomp_rule_add.argtypes = [ctypes.c_void_p, ctypes.c_uint32, ctypes.c_int, ctypes.c_uint]
    lib.seccomp_export_bpf.argtypes = [ctypes.c_void_p, ctypes.c_int]
    allow, refuse = 0x7FFF0000, 0x00050000 | errno.EPERM  # SCMP_ACT_ALLOW, SCMP_ACT_ERRNO
    ctx = lib.seccomp_init(allow)
    if not ctx:
        return None
    try:
        for arch in _COMPAT_ARCHES.get(platform.machine(), ()):
            token = lib.seccomp_arch_resolve_name(arch.encode())
            if token:
                lib.seccomp_arch_add(ctx, token)  # -EEXIST where it is the native one
        for call in KEY_CALLS:
            number = lib.seccomp_syscall_resolve_name(call.encode())
            if number < 0 or lib.seccomp_rule_add(ctx, refuse, number, 0) != 0:
                return None
        fd = os.memfd_create("usar-seccomp", os.MFD_CLOEXEC)
        try:
            if lib.seccomp_export_bpf(ctx, fd) != 0:
                return None
            os.lseek(fd, 0, os.SEEK_SET)
            return _read_all(fd)
        finally:
            os.close(fd)
    finally:
        lib.seccomp_release(ctx)


def _read_all(fd: int) -> bytes:
    out = bytearray()
    while block := os.read(fd, 65536):
        out += block
    return bytes(out)


def keyring_filter_fd() -> int | None:
    """A new file descriptor (at offset 0; close-on-exec, which ``Popen(pass_fds=...)`` lifts
    in the child alone) holding :func:`keyring_filter`, for bwrap's ``--seccomp FD``; the
    caller closes it once bwrap has started. None where there is no filter here."""
    program = keyring_filter()
    if program is None:
        return None
    fd = os.memfd_create("usar-seccomp", os.MFD_CLOEXEC)
    try:
        os.write(fd, program)
        os.lseek(fd, 0, os.SEEK_SET)
    except OSError:
        with contextlib.suppress(OSError):
            os.close(fd)
        return None
    return fd
