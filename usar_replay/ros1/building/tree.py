"""A built workspace as usar trusts it: checked, frozen, listed, and verified before reuse.

Why: a package's build is the team's code (``execute_process`` in its CMakeLists.txt runs at
configure time), and the workspace it leaves is what the run mounts and what a later run of the
same bytes reuses. So, once the build's sandbox is gone and before usar uses the workspace:

- :func:`check` refuses what a build may have planted for usar to trip on: a link that leads
  out of the workspace (usar or a later run would read or write through it), and special files
  (FIFOs block a reader, sockets and devices are nobody's build output);
- :func:`freeze` takes every write bit and set-id bit off, so that nothing but usar (root, or
  the user who owns it) can change it, and a set-uid binary made by a build is not one;
- :func:`manifest` lists every entry (type, mode, sha256 of the bytes, a link's target); it is
  kept beside the workspace, in a folder no sandbox ever sees, and :func:`verify` compares a
  cached workspace against it before it is reused: a reused build is verified, not trusted.

Nothing here follows a link: entries are read with ``lstat`` and files opened ``O_NOFOLLOW``.
"""

from __future__ import annotations

import hashlib
import os
import stat
from pathlib import Path

from usar_replay.core.errors import TreeRefused
from usar_replay.core.folder_walk import shown

__all__ = ["TreeRefused", "check", "freeze", "manifest", "verify", "write_new"]


def _walk(root: str) -> list[tuple[str, os.stat_result]]:
    """Every entry under ``root`` (relative path, lstat), sorted, never through a link."""
    out: list[tuple[str, os.stat_result]] = []
    stack = [""]
    while stack:
        rel = stack.pop()
        with os.scandir(os.path.join(root, rel)) as it:
            entries = sorted(it, key=lambda e: e.name)
        for entry in entries:
            sub = f"{rel}/{entry.name}" if rel else entry.name
            st = entry.stat(follow_symlinks=False)
            out.append((sub, st))
            if stat.S_ISDIR(st.st_mode):
                stack.append(sub)
    return sorted(out)


def _inside(path: str, root: str) -> bool:
    return path == root or path.startswith(root.rstrip("/") + "/")


def check(root: Path) -> None:
    """Raise :class:`TreeRefused` for a special file or a link leading out of ``root``."""
    real_root = os.path.realpath(root)
    for rel, st in _walk(str(root)):
        mode = st.st_mode
        if stat.S_ISLNK(mode):
            target = os.readlink(os.path.join(root, rel))
            if not _inside(os.path.realpath(os.path.join(root, rel)), real_root):
                raise TreeRefused(
                    "the build left a link that leaves its workspace: "
                    f"{shown(rel)} -> {shown(target)}"[:300]
                )
        elif not (stat.S_ISREG(mode) or stat.S_ISDIR(mode)):
            kind = "FIFO" if stat.S_ISFIFO(mode) else "socket" if stat.S_ISSOCK(mode) else "device"
            raise TreeRefused(f"the build left a {kind} in its workspace: {shown(rel)}"[:300])


def freeze(root: Path) -> None:
    """Every file and folder of ``root`` read-only for all, set-id bits off (links as they
    are: a link has no mode of its own). Folders last, deepest first."""
    entries = _walk(str(root))
    for rel, st in entries:
        if stat.S_ISREG(st.st_mode):
            os.chmod(
                os.path.join(root, rel), stat.S_IMODE(st.st_mode) & 0o555, follow_symlinks=False
            )
    for rel, st in sorted(entries, reverse=True):
        if stat.S_ISDIR(st.st_mode):
            os.chmod(os.path.join(root, rel), 0o555, follow_symlinks=False)
    os.chmod(root, 0o555)


def _sha256(path: str) -> str:
    h = hashlib.sha256()
    fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC)
    with os.fdopen(fd, "rb") as f:
        if not stat.S_ISREG(os.fstat(f.fileno()).st_mode):
            raise TreeRefused(f"{path}: not a regular file")
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def manifest(root: Path) -> dict[str, str]:
    """``relative path -> what it is``: ``d <mode>``, ``f <mode> <sha256>``, ``l <target>``
    (``.`` is the root itself)."""
    out = {".": f"d {stat.S_IMODE(os.lstat(root).st_mode):o}"}
    for rel, st in _walk(str(root)):
        mode = stat.S_IMODE(st.st_mode)
        full = os.path.join(root, rel)
        if stat.S_ISLNK(st.st_mode):
            out[rel] = f"l {os.readlink(full)}"
        elif stat.S_ISDIR(st.st_mode):
            out[rel] = f"d {mode:o}"
        elif stat.S_ISREG(st.st_mode):
            out[rel] = f"f {mode:o} {_sha256(full)}"
        else:
            out[rel] = "special"
    return out


def verify(root: Path, expected: dict[str, str]) -> str:
    """'' when ``root`` is exactly as listed, else the first difference (one line)."""
    try:
        found = manifest(root)
    except (OSError, TreeRefused) as err:
        return f"cannot list it ({err})"
    for rel in sorted(set(found) | set(expected)):
        if found.get(rel) != expected.get(rel):
            return f"{rel} changed since it was built"
    return ""


def write_new(path: Path, text: str) -> None:
    """Create ``path`` (it must not exist, never through a link) with ``text``, read-only."""
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW | os.O_CLOEXEC, 0o444)
    with os.fdopen(fd, "w", encoding="utf-8") as f:
        f.write(text)
