"""``/proc/self/mountinfo`` as its fields, one :class:`Mount` a line.

Why one reader: the cgroup backends ask where a hierarchy is mounted and from which root (a
container sharing the host's cgroup namespace mounts only its own subtree), the container check
asks which cgroup mounts are read-only, and the run folder which mounts lie below it. Each had
its own split of the line and its own partial undoing of the kernel's octal escapes.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass

__all__ = ["Mount", "parse", "read", "unescape"]

PATH = "/proc/self/mountinfo"


@dataclass(frozen=True, slots=True)
class Mount:
    """One line: ``ID PARENT MAJ:MIN ROOT POINT OPTIONS [OPTIONAL...] - FSTYPE SOURCE SUPER``."""

    root: str
    """The folder of the file system shown at :attr:`point` (``/docker/<id>`` for a subtree)."""
    point: str
    options: tuple[str, ...]
    """The mount's own options (``ro``, ``rw``, ``nosuid``, ...)."""
    fstype: str
    super_options: tuple[str, ...]
    """The file system's options: cgroup v1's name its controllers (``rw,memory``)."""


def unescape(field: str) -> str:
    """A mountinfo field with the kernel's octal escapes (space, tab, newline, backslash)
    undone."""
    return re.sub(r"\\([0-7]{3})", lambda m: chr(int(m.group(1), 8)), field)


def parse(text: str) -> list[Mount]:
    """Every well-formed line of ``text`` (the file's contents), in order; others are left out."""
    out = []
    for line in text.splitlines():
        head, sep, tail = line.partition(" - ")
        fields, after = head.split(), tail.split()
        if not sep or len(fields) < 6 or not after:
            continue
        out.append(
            Mount(
                root=unescape(fields[3]),
                point=unescape(fields[4]),
                options=tuple(fields[5].split(",")),
                fstype=after[0],
                super_options=tuple(after[2].split(",")) if len(after) > 2 else (),
            )
        )
    return out


def read() -> str:
    """This process's mountinfo text ('' where it cannot be read); names that are not UTF-8
    kept as the file system's encoding keeps them (:func:`os.fsdecode`)."""
    try:
        with open(PATH, "rb") as f:
            return os.fsdecode(f.read())
    except OSError:
        return ""
