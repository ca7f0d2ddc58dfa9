"""Reading a team's folder without trusting it: regular files only, no links out, bounded.

Why: ``usar batch`` digests every team's folder before any run (the digest decides what a resume
runs again), as root, on a class's hand-ins. A plain ``read_bytes()`` of every file hangs on a
FIFO, never ends on a link to ``/dev/zero`` and dies of ``MemoryError`` on a 30 GB sparse file:
then nobody is graded. Here every file is opened with ``O_NOFOLLOW | O_NONBLOCK`` and checked to
be a regular file on the opened descriptor (``fstat``), links are never followed (a link that
stays inside the folder is digested as its text; one that leaves it makes the folder unusable),
and bytes are streamed with a cap per file and per folder. A folder that breaks a rule raises
:class:`UnusableSubmission`, which the batch turns into that team's verdict
(``bad_submission``) while every other team is graded.

The digest of an honest folder is the one ``usar batch`` always computed (sorted relative
paths, each with its length and bytes), so finished runs are still recognised on resume.
"""

from __future__ import annotations

import hashlib
import os
import stat
from pathlib import Path

from usar_replay.core.errors import UnusableSubmission

__all__ = [
    "MAX_FILE_BYTES",
    "MAX_FILES",
    "MAX_TOTAL_BYTES",
    "UnusableSubmission",
    "submission_digest",
]

MAX_FILE_BYTES = 256 * 1024 * 1024
"""The largest file a team's folder may hold (256 MiB: a mission's code, a model of a few MiB)."""
MAX_TOTAL_BYTES = 1024 * 1024 * 1024
"""All of a team's files together (1 GiB)."""
MAX_FILES = 20_000
"""Files (and links) a team's folder may hold."""
SKIP_DIRS = frozenset({"__pycache__", ".git", ".hg", ".svn"})
"""Folders left out of the digest (caches, version control), as are hidden names and .pyc."""
_CHUNK = 1024 * 1024


def _skipped(name: str) -> bool:
    return name.startswith(".") or name.endswith(".pyc")


def _entries(root: Path) -> list[tuple[str, Path, bool]]:
    """(relative path, path, is a link) of every file and link under ``root``, never through a
    link; special files raise."""
    found: list[tuple[str, Path, bool]] = []
    stack = [root]
    while stack:
        folder = stack.pop()
        with os.scandir(folder) as it:
            items = sorted(it, key=lambda e: e.name)
        for e in items:
            path = Path(e.path)
            rel = path.relative_to(root).as_posix()
            if e.is_symlink():
                if not _skipped(e.name):
                    found.append((rel, path, True))
            elif e.is_dir(follow_symlinks=False):
                if e.name not in SKIP_DIRS and not e.name.startswith("."):
                    stack.append(path)
            elif e.is_file(follow_symlinks=False):
                if not _skipped(e.name):
                    found.append((rel, path, False))
            elif not e.name.startswith("."):
                raise UnusableSubmission(f"{rel}: not a regular file (a FIFO, socket or device)")
            if len(found) > MAX_FILES:
                raise UnusableSubmission(f"more than {MAX_FILES} files")
    return found


def _link_text(root: Path, rel: str, path: Path) -> bytes:
    """A link's target, when it stays inside ``root`` (resolved without opening anything)."""
    target = os.readlink(path)
    real = Path(os.path.realpath(path))
    if not real.is_relative_to(os.path.realpath(root)):
        raise UnusableSubmission(f"{rel}: a link leaving the team's folder (to {target})")
    return os.fsencode(target)


def _stream(h: hashlib._Hash, path: Path, rel: str, prefix: bytes, budget: int) -> int:
    """Hash ``prefix``, the file's length and its bytes, read from a descriptor that is
    checked to be a regular file; returns its size."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError as err:
        raise UnusableSubmission(f"{rel}: cannot be opened ({err.strerror})") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise UnusableSubmission(f"{rel}: not a regular file")
        size = st.st_size
        if size > MAX_FILE_BYTES:
            raise UnusableSubmission(f"{rel}: {size} bytes; a file is at most {MAX_FILE_BYTES}")
        if size > budget:
            raise UnusableSubmission(f"the team's files are over {MAX_TOTAL_BYTES} bytes")
        if prefix:  # a folder's file: its name and length first (a single file: bytes only)
            h.update(prefix + size.to_bytes(8, "little"))
        left = size
        while left > 0:
            chunk = os.read(fd, min(_CHUNK, left))
            if not chunk:
                break
            h.update(chunk)
            left -= len(chunk)
        if left or os.read(fd, 1):
            raise UnusableSubmission(f"{rel}: changed while it was read")
        return size
    finally:
        os.close(fd)


def submission_digest(path: str | os.PathLike[str]) -> str:
    """sha256 over every file of a submission (relative path and bytes, sorted), so that a
    change in any helper module reruns the team; caches and hidden files are left out.
    :class:`UnusableSubmission` when the folder breaks a rule (see the module doc)."""
    root = Path(path)
    h = hashlib.sha256()
    if not root.is_dir():
        _stream(h, root, root.name, b"", MAX_FILE_BYTES)
        return h.hexdigest()
    budget = MAX_TOTAL_BYTES
    for rel, file, is_link in sorted(_entries(root), key=lambda x: x[0]):
        name = rel.encode()
        prefix = len(name).to_bytes(4, "little") + name
        if is_link:
            text = _link_text(root, rel, file)
            h.update(prefix + len(text).to_bytes(8, "little") + text)
            continue
        budget -= _stream(h, file, rel, prefix, budget)
    return h.hexdigest()
