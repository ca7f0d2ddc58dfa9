"""A folder handed in (a team's, a ``--ros1`` package), walked once without trusting it.

Why one walk: ``usar batch`` digests a team's folder, and the ROS 1 build hashes and copies
the package in it. When each read the folder its own way, a hidden ``.cache/blob.bin`` of
2 GiB (sparse) was skipped by the batch's checks and then read and copied by the build
(issue 33). Here one walk decides which entries exist, under one set of rules and caps, and
every reader (:mod:`usar_replay.batch.team_files`,
:mod:`usar_replay.ros1.building.workspace`) takes its
list: what is checked is what is hashed, copied and built.

The rules: links are never followed (one that stays inside is kept as its text, one that
leaves refuses the folder, except catkin's own, left out: :func:`catkin_link`), hidden names,
``.pyc`` files and cache or version-control folders are left out unread, any other entry
that is not a folder or a regular file (a FIFO, a socket, a device) refuses the folder, and the
number of entries, each file's size and the total are capped from ``lstat`` before a byte is
read (a sparse file is refused unread).
Files are then read from a descriptor opened ``O_NOFOLLOW | O_NONBLOCK`` and checked to be
the regular file of the size the walk saw. Names are bytes: a name that is not UTF-8 (an
old zip's ``caf\\xe9.txt``) is hashed as its bytes and quoted escaped, never a crash. A rule
broken raises :class:`~usar_replay.core.errors.UnusableSubmission` whose text is safe to print.
"""

from __future__ import annotations

import os
import re
import stat
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from usar_replay.core.errors import UnusableSubmission
from usar_replay.core.safe_text import safe_line

__all__ = [
    "MAX_FILES",
    "MAX_FILE_BYTES",
    "MAX_TOTAL_BYTES",
    "SKIP_DIRS",
    "Entry",
    "catkin_link",
    "linked",
    "shown",
    "stream",
    "walk",
]

MAX_FILE_BYTES = 256 * 1024 * 1024
"""The largest file a folder may hold (256 MiB: a mission's code, a model of a few MiB)."""
MAX_TOTAL_BYTES = 1024 * 1024 * 1024
"""All of a folder's files together (1 GiB)."""
MAX_FILES = 20_000
"""Files (and links) a folder may hold."""
SKIP_DIRS = frozenset({"__pycache__", ".git", ".hg", ".svn"})
"""Folders left out unread (caches, version control), as are hidden names and ``.pyc``."""
_CHUNK = 1024 * 1024
_CATKIN_LINKS: dict[bytes, re.Pattern[bytes]] = {
    b"CMakeLists.txt": re.compile(
        rb"(/opt/ros/[A-Za-z0-9_-]+|/usr)/share/catkin/cmake/toplevel\.cmake"
    ),
}
"""The links a catkin workspace ships that leave it, by name and target: ``catkin_make`` (and
``catkin_init_workspace``) link ``src/CMakeLists.txt`` to catkin's ``toplevel.cmake`` of the
ROS install (``/opt/ros/<distro>/...``, Debian's ``/usr/share/catkin/...``)."""


def linked(names: list[str]) -> str:
    """What a team's entry that is a link is told (one line; ``usar batch`` and ``usar code``
    say the same): a class folder's team is read only as a real folder (or file), never
    through a link, which could lead anywhere on the machine. ``names``: shown names."""
    first = ", ".join(names[:4]) + (f" and {len(names) - 4} more" if len(names) > 4 else "")
    one = len(names) == 1
    return (
        f"{first} {'is a link' if one else 'are links'}: usar reads only real folders, never "
        f"through a link; copy {'it' if one else 'each'} in its place (cp -rL) and grade again"
    )


def catkin_link(rel: bytes, target: bytes) -> bool:
    """Is the link ``rel`` (to ``target``, as ``readlink`` gives it) one that catkin itself
    puts in every workspace (:data:`_CATKIN_LINKS`), not the team's? Such a link is left out
    of the walk, never followed nor copied, and the team read on the rest (issue 51): a
    committed ``catkin_make`` workspace is a normal hand-in. Decided on the link's text only."""
    pattern = _CATKIN_LINKS.get(os.path.basename(rel))
    return pattern is not None and pattern.fullmatch(target) is not None


def shown(name: str | bytes) -> str:
    """A file name as text that is safe on a terminal and in a log (UTF-8): bytes that are
    not UTF-8 and control characters written as escapes."""
    raw = name if isinstance(name, bytes) else os.fsencode(name)
    return safe_line(raw.decode("utf-8", "backslashreplace"))


@dataclass(frozen=True, slots=True)
class Entry:
    """One file or link of a walked folder."""

    rel: bytes
    """Its path relative to the folder, as bytes (``/``-separated): what a digest hashes."""
    path: Path
    size: int
    """A file's size as the walk saw it (0 for a link)."""
    link: bytes | None = None
    """A link's target (one that stays inside the folder), else None."""

    @property
    def rel_path(self) -> Path:
        return Path(os.fsdecode(self.rel))


def _skipped(name: bytes) -> bool:
    return name.startswith(b".") or name.endswith(b".pyc")


def _link(root: Path, rel: bytes, path: Path, what: str) -> bytes | None:
    """A link's target, when it stays inside ``root`` (resolved without opening anything);
    None for catkin's own link out (:func:`catkin_link`)."""
    target = os.readlink(os.fsencode(path))
    real = Path(os.path.realpath(path))
    if not real.is_relative_to(os.path.realpath(root)):
        if catkin_link(rel, target):
            return None
        raise UnusableSubmission(f"{shown(rel)}: a link leaving {what} (to {shown(target)})")
    return target


def walk(
    root: str | os.PathLike[str],
    *,
    skip_dirs: frozenset[str] = SKIP_DIRS,
    max_files: int = MAX_FILES,
    max_file_bytes: int = MAX_FILE_BYTES,
    max_total_bytes: int = MAX_TOTAL_BYTES,
    what: str = "the folder",
    left_out: list[str] | None = None,
) -> list[Entry]:
    """Every file and link under ``root`` by the module's rules, sorted by relative path (as
    bytes); folders named in ``skip_dirs`` are left out unread, and catkin's own links out
    (:func:`catkin_link`) too, each said in ``left_out`` when given. Raises
    :class:`UnusableSubmission` at the first rule broken (``what``: the folder, in its words)."""
    top = os.fsencode(root)
    skip = frozenset(os.fsencode(d) for d in skip_dirs)
    found: list[Entry] = []
    total = 0
    stack = [b""]
    while stack:
        rel_dir = stack.pop()
        folder = os.path.join(top, rel_dir) if rel_dir else top
        try:
            with os.scandir(folder) as it:
                items = sorted(it, key=lambda e: e.name)
        except OSError as err:
            where = shown(rel_dir) if rel_dir else "the folder"
            raise UnusableSubmission(f"{where}: cannot be read ({err.strerror})") from None
        for e in items:
            name = e.name
            rel = os.path.join(rel_dir, name) if rel_dir else name
            try:
                st = os.lstat(e.path)
            except OSError as err:
                raise UnusableSubmission(f"{shown(rel)}: {err.strerror}") from None
            if stat.S_ISDIR(st.st_mode):
                if name not in skip and not name.startswith(b"."):
                    stack.append(rel)
                continue
            if _skipped(name):
                continue
            path = Path(os.fsdecode(e.path))
            if stat.S_ISLNK(st.st_mode):
                target = _link(Path(os.fsdecode(top)), rel, path, what)
                if target is None:  # catkin's own: left out, never followed nor copied
                    if left_out is not None:
                        left_out.append(
                            f"{shown(rel)}: catkin's link out of the workspace, left out"
                        )
                    continue
                found.append(Entry(rel, path, 0, target))
            elif stat.S_ISREG(st.st_mode):
                if st.st_size > max_file_bytes:
                    raise UnusableSubmission(
                        f"{shown(rel)}: {st.st_size} bytes; a file is at most {max_file_bytes}"
                    )
                total += st.st_size
                if total > max_total_bytes:
                    raise UnusableSubmission(
                        f"the files of {what} are over {max_total_bytes} bytes"
                    )
                found.append(Entry(rel, path, st.st_size))
            else:
                raise UnusableSubmission(
                    f"{shown(rel)}: not a regular file (a FIFO, socket or device)"
                )
            if len(found) > max_files:
                raise UnusableSubmission(f"more than {max_files} files")
    found.sort(key=lambda x: x.rel)
    return found


def stream(entry: Entry, sink: Callable[[bytes], object]) -> int:
    """Hand the bytes of ``entry`` (a file) to ``sink``, read from a descriptor checked to be
    the regular file of the size :func:`walk` saw; returns its mode bits."""
    try:
        fd = os.open(entry.path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError as err:
        raise UnusableSubmission(f"{shown(entry.rel)}: cannot be opened ({err.strerror})") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode) or st.st_size != entry.size:
            raise UnusableSubmission(f"{shown(entry.rel)}: changed while it was read")
        left = entry.size
        while left > 0:
            chunk = os.read(fd, min(_CHUNK, left))
            if not chunk:
                break
            sink(chunk)
            left -= len(chunk)
        if left or os.read(fd, 1):
            raise UnusableSubmission(f"{shown(entry.rel)}: changed while it was read")
        return stat.S_IMODE(st.st_mode)
    finally:
        os.close(fd)
