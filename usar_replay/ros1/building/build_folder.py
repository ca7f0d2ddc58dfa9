"""The build's workspace as a size- and inode-limited tmpfs while catkin runs (issue 44).

Why: a package's ``CMakeLists.txt`` is the team's code, and its build wrote 2 x 1000 MiB and
150,000 files into a plain folder on the host's disk (a per-file limit only), was called a
success and stayed in the build cache for good. Now the workspace is a tmpfs of
``--build-folder`` MiB and :data:`BUILD_FOLDER_INODES` files while the build runs (its pages
are charged to the build's memory cgroup, so ``--run-memory`` covers them too). A build that
fills it is ``build_failed`` with the limit named, and nothing of it is kept; a build within the
caps is copied to the disk folder it was built in (the same path: catkin writes absolute paths
into ``devel/``), the tmpfs unmounted, and only then sealed into the cache.

Where nothing can be mounted (not root) the workspace is the plain folder as before;
:attr:`BuildFolder.limited` says which (``usar doctor`` says whether this machine mounts).
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

from usar_replay.core.limits import RunLimits
from usar_replay.sandbox.run_folder import mount_tmpfs, tmpfs_full, unmount

__all__ = ["BUILD_FOLDER_INODES", "DEFAULT_BUILD_FOLDER_MB", "BuildFolder"]

DEFAULT_BUILD_FOLDER_MB = RunLimits().build_folder_mb
"""The build folder's default size, MiB (``--build-folder``): the course template's build is
some 60 MiB, usar's underlay some 20 MiB."""
BUILD_FOLDER_INODES = 100_000
"""Files and folders the build may make (the template's build: some 2,000)."""
_FREE_INODES = 64


class BuildFolder:
    """``ws`` (an empty folder) made a tmpfs of ``size_mb`` MiB when one can be mounted
    (0: none); :meth:`keep` copies what was built to the disk and unmounts, :meth:`close`
    unmounts and drops it."""

    def __init__(self, ws: Path, size_mb: int, inodes: int = BUILD_FOLDER_INODES) -> None:
        self.ws = ws
        self.size_mb = size_mb
        self.inodes = inodes
        self.limited = size_mb > 0 and mount_tmpfs(
            str(ws), size_mb * 1024 * 1024, inodes=inodes
        )

    def full(self) -> bool:
        """Did the build fill its folder (its space or its files)? Only a limited one can."""
        return self.limited and tmpfs_full(str(self.ws), self.size_mb, min_inodes=_FREE_INODES)

    def limit_words(self) -> str:
        """The cap as a build_failed line names it."""
        return (
            f"its build folder ({self.size_mb} MiB and {self.inodes:,} files: --build-folder)"
        )

    def keep(self) -> None:
        """What was built, copied to the disk folder at the same path, the tmpfs gone (links
        copied as links: :func:`usar_replay.ros1.building.tree.check` judged them before)."""
        if not self.limited:
            return
        staged = self.ws.with_name(self.ws.name + ".disk")
        shutil.copytree(self.ws, staged, symlinks=True)
        self.close()
        os.rmdir(self.ws)
        os.rename(staged, self.ws)

    def close(self) -> None:
        """Unmount (lazily), leaving the empty folder; what the tmpfs held is gone."""
        if self.limited:
            unmount(str(self.ws))
            self.limited = False
