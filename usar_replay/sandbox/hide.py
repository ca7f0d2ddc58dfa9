"""The grader's files, found wherever they lie in what the sandbox mounts, so they can be hidden.

Why: a mission's folder is mounted read-only for it (a Python mission may import modules kept
beside it), and a grader often keeps the world, the world key, the settings, the thresholds or
the output right there. The sandbox then mounts ``/dev/null`` over each such file and an empty
read-only folder over each such folder (:func:`usar_replay.sandbox.kernel_sandbox.sandbox_argv`), so
the mission sees its own files and never one the grader passed in.

Found by what they are, not by the name given: a path is resolved (symlinks, ``..``), and a
file with more than one hard link has its other names looked for in the mission's folders (by
device and inode), which a plain path comparison would miss. The search is bounded: a folder too
large to search is refused (a :class:`UsageError`), never mounted unchecked.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Sequence

from usar_replay.core.errors import UsageError

__all__ = ["MAX_SEARCHED", "Hidden", "grader_files"]

MAX_SEARCHED = 50_000
"""Entries searched for another name of a hard-linked grader file before giving up."""

Hidden = tuple[tuple[str, ...], tuple[str, ...]]
"""(files, folders) to hide, as real paths."""


def _under(path: str, roots: Iterable[str]) -> bool:
    return any(path == r or path.startswith(r.rstrip(os.sep) + os.sep) for r in roots)


def grader_files(paths: Sequence[str], roots: Sequence[str]) -> Hidden:
    """The real paths to hide of ``paths`` (what the grader passed in; missing ones skipped),
    with every other name of a hard-linked file found under ``roots`` (the mission's folders)."""
    files: dict[str, None] = {}
    folders: dict[str, None] = {}
    linked: set[tuple[int, int]] = set()
    for given in paths:
        if not given:
            continue
        real = os.path.realpath(given)
        try:
            st = os.stat(real)
        except OSError:
            continue
        if os.path.isdir(real):
            folders[real] = None
        else:
            files[real] = None
            if st.st_nlink > 1:
                linked.add((st.st_dev, st.st_ino))
    if linked:
        for twin in _other_names(linked, roots, [*files, *paths]):
            files[twin] = None
    return tuple(files), tuple(folders)


def _other_names(
    linked: set[tuple[int, int]], roots: Sequence[str], named: Sequence[str]
) -> list[str]:
    """Every file under ``roots`` that is one of ``linked`` (device, inode)."""
    found: list[str] = []
    seen = 0
    for root in dict.fromkeys(os.path.realpath(r) for r in roots):
        for folder, dirs, names in os.walk(root):
            seen += len(dirs) + len(names)
            if seen > MAX_SEARCHED:
                raise UsageError(
                    f"{named[0]} has another name (a hard link) and {root} is too large to "
                    f"search for it (over {MAX_SEARCHED} entries); keep the grader's files "
                    "outside the mission's folder"
                )
            for name in names:
                path = os.path.join(folder, name)
                try:
                    st = os.lstat(path)
                except OSError:
                    continue
                if (st.st_dev, st.st_ino) in linked:
                    found.append(path)
    return found
