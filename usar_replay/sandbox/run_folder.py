"""A run's writable folder as a size-limited tmpfs: the run's files have one total limit.

Why: the sandboxed run writes only its own folder (and its private ``/tmp`` and ``/dev/shm``,
tmpfs mounts of their own size). On the host's disk that folder had only a per-file limit
(RLIMIT_FSIZE), so a run could fill the disk with many files. A tmpfs with ``size=`` mounted
on the folder (by the recorder, which is root; the sandbox binds it as it bound the plain folder)
caps the total; its pages are charged to the memory cgroup of the process that writes them,
so the run's memory limit covers them too (:mod:`.kernel_sandbox`). A run that fills it ends
``refused`` (:meth:`RunFolder.full`, checked by :mod:`.mission_process` after each tick).

Where nothing can be mounted (not root) the folder is a plain one and only the per-file limit
applies, as before; :attr:`RunFolder.limited` says which.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os
import shutil
import tempfile

from usar_replay.core.limits import RunLimits
from usar_replay.sandbox import mountinfo

__all__ = [
    "DEFAULT_RUN_FOLDER_MB",
    "RunFolder",
    "mount_tmpfs",
    "tmpfs_full",
    "unmount",
    "unmount_under",
]

DEFAULT_RUN_FOLDER_MB = RunLimits().run_folder_mb
"""The run folder's default size in MiB (``--run-folder-mb``)."""

_MNT_DETACH = 2
_MS_NOSUID = 2
_MS_NODEV = 4
_FULL_BYTES = 1 << 20
"""Less than this free: the folder is full (a filler's last write failed for want of space)."""


def _libc() -> ctypes.CDLL | None:
    name = ctypes.util.find_library("c")
    return ctypes.CDLL(name, use_errno=True) if name else None


def mount_tmpfs(path: str, size_bytes: int, *, inodes: int = 0) -> bool:
    """A tmpfs of ``size_bytes`` (and ``inodes`` files, 0: tmpfs's default) on the folder at
    ``path``, nosuid and nodev, mode 0700; False where nothing can be mounted (not root)."""
    libc = _libc()
    if libc is None or os.geteuid() != 0:
        return False
    opts = f"size={size_bytes},mode=0700" + (f",nr_inodes={inodes}" if inodes else "")
    done = libc.mount(b"tmpfs", path.encode(), b"tmpfs", _MS_NOSUID | _MS_NODEV, opts.encode())
    return bool(done == 0)


def tmpfs_full(path: str, size_mb: int, *, min_inodes: int = 0) -> bool:
    """Has what was written filled the tmpfs of ``size_mb`` MiB at ``path``: less room left
    than a filler's last write needs, or (``min_inodes``) fewer files than that?"""
    try:
        st = os.statvfs(path)
    except OSError:
        return False
    if st.f_bavail * st.f_frsize < min(_FULL_BYTES, size_mb * 1024 * 16):
        return True
    return st.f_favail < min_inodes


def unmount(path: str) -> None:
    """Unmount ``path`` lazily (a process that still has a file open does not stop it)."""
    libc = _libc()
    if libc is not None:
        libc.umount2(path.encode(), _MNT_DETACH)


class RunFolder:
    """A fresh folder (``mkdtemp``), a tmpfs of ``size_mb`` MiB on it when one can be mounted
    (0: none); :meth:`close` unmounts and removes it."""

    def __init__(self, prefix: str, size_mb: int) -> None:
        self.path = tempfile.mkdtemp(prefix=prefix)
        self.size_mb = size_mb
        self.limited = size_mb > 0 and self._mount()

    def _mount(self) -> bool:
        return mount_tmpfs(self.path, self.size_mb * 1024 * 1024)

    def full(self) -> bool:
        """Has the run filled its folder? (only a size-limited one can be full)"""
        return self.limited and tmpfs_full(self.path, self.size_mb)

    def close(self, keep: bool = False) -> None:
        """Unmount (lazily: a process that still has a file open does not stop it) and remove
        the folder; ``keep`` leaves a plain folder's files (a mounted one's go with it)."""
        if self.limited:
            unmount(self.path)
            self.limited = False
        if not keep:
            shutil.rmtree(self.path, ignore_errors=True)


def _mount_points() -> list[str]:
    """This mount namespace's mount points, their escapes undone (:mod:`.mountinfo`)."""
    return [m.point for m in mountinfo.parse(mountinfo.read())]


def unmount_under(folder: str) -> list[str]:
    """Unmount (lazily) every mount at or below ``folder``, the deepest first; returns them.
    Why: a run killed at its wall limit never reaches :meth:`RunFolder.close`, and its tmpfs
    stayed mounted in the batch's work folder (``rmtree`` could not remove it) until the
    machine restarted. The batch calls this once the run's processes are gone."""
    libc = _libc()
    if libc is None or os.geteuid() != 0:
        return []
    top = os.path.realpath(folder)
    under = [m for m in _mount_points() if m == top or m.startswith(top + os.sep)]
    for point in sorted(under, key=len, reverse=True):
        libc.umount2(point.encode(), _MNT_DETACH)
    return under
