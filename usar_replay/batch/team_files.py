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

The walk itself, its rules and caps are :mod:`usar_replay.core.folder_walk`'s: the ROS 1 build
hashes and copies a package from the same walk, so what is checked here is what is built, and
a name that is not UTF-8 is hashed as its bytes (issue 33).

The digest of an honest folder is the one ``usar batch`` always computed (sorted relative
paths, each with its length and bytes), so finished runs are still recognised on resume.
"""

from __future__ import annotations

import hashlib
import os
import stat
from pathlib import Path

from usar_replay.core.errors import UnusableSubmission
from usar_replay.core.folder_walk import (
    MAX_FILE_BYTES,
    MAX_FILES,
    MAX_TOTAL_BYTES,
    SKIP_DIRS,
    Entry,
    shown,
    stream,
    walk,
)

__all__ = [
    "MAX_FILES",
    "MAX_FILE_BYTES",
    "MAX_TOTAL_BYTES",
    "SKIP_DIRS",
    "UnusableSubmission",
    "submission_digest",
]


def _single(path: Path) -> Entry:
    """A submission that is one file, checked like a folder's file."""
    try:
        st = os.lstat(path)
    except OSError as err:
        raise UnusableSubmission(f"{shown(path.name)}: {err.strerror}") from None
    if not stat.S_ISREG(st.st_mode):
        raise UnusableSubmission(f"{shown(path.name)}: not a regular file")
    if st.st_size > MAX_FILE_BYTES:
        raise UnusableSubmission(
            f"{shown(path.name)}: {st.st_size} bytes; a file is at most {MAX_FILE_BYTES}"
        )
    return Entry(os.fsencode(path.name), path, st.st_size)


def submission_digest(path: str | os.PathLike[str]) -> str:
    """sha256 over every file of a submission (relative path as bytes, and bytes, sorted), so
    that a change in any helper module reruns the team; caches and hidden files are left out.
    :class:`UnusableSubmission` when the folder breaks a rule (see the module doc)."""
    root = Path(path)
    h = hashlib.sha256()
    if not root.is_dir() or root.is_symlink():
        stream(_single(root), h.update)
        return h.hexdigest()
    for entry in walk(root, what="the team's folder"):
        prefix = len(entry.rel).to_bytes(4, "little") + entry.rel
        if entry.link is not None:
            h.update(prefix + len(entry.link).to_bytes(8, "little") + entry.link)
            continue
        h.update(prefix + entry.size.to_bytes(8, "little"))
        stream(entry, h.update)
    return h.hexdigest()
