"""Where a built ROS 1 workspace appears inside the kernel sandbox: fixed paths, not the host's.

Why: catkin writes the workspace's absolute path into what it builds (``devel/setup.sh``, the
``*.cmake`` files), and a C++ node carries its source file's absolute path (``__FILE__``) into
every ``/rosout`` message's ``file`` field. Built and run at the host folder of usar's build
cache (``$XDG_CACHE_HOME/usar/ros1/<pkg>-<key>/ws``, or a batch's private folder with a random
name), the same package on the same world would log different bytes for another user, another
machine or another batch engine, and ``usar replay`` elsewhere would report a divergence.

So, in the sandbox's own mount namespace, the build and the run see the package's workspace at
:data:`WORKSPACE` and usar's underlay (``fiducial_msgs``) at :data:`UNDERLAY`, whatever host
folders hold them (:func:`usar_replay.sandbox.kernel_sandbox.sandbox_argv`'s ``ro_mounts`` and
``work_at``). A workspace built there works only mounted there, so the layout is part of the
build cache's key (:data:`VERSION`). Without a kernel sandbox (no bubblewrap, or
``USAR_SANDBOX=off``) there is no mount namespace: the build and the run use the host's paths,
as before, and only sandboxed runs are path-independent (docs/ros1.md).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

__all__ = ["HOST", "UNDERLAY", "VERSION", "WORKSPACE", "mounts", "underlay_at"]

WORKSPACE = "/ros1/ws"
"""The package's workspace inside the sandbox (the build writes it; the run reads it)."""

UNDERLAY = "/ros1/underlay"
"""usar's underlay workspace (``fiducial_msgs``) inside the sandbox, read-only."""

VERSION = "ros1-fixed-1"
"""The in-sandbox layout, in the build cache's key: change it when the paths above change."""

HOST = "host"
"""The cache key's layout word for a workspace built at its host path (no sandbox)."""


def underlay_at(index: int) -> str:
    """Where the ``index``-th underlay appears (usar has one: :data:`UNDERLAY`)."""
    return UNDERLAY if index == 0 else f"{UNDERLAY}{index + 1}"


def mounts(underlays: Sequence[Path]) -> tuple[tuple[str, str], ...]:
    """(host folder, path in the sandbox) of each underlay, read-only."""
    return tuple((str(u), underlay_at(i)) for i, u in enumerate(underlays))
