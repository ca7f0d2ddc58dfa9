"""A team's files for the code grade, read once without trusting them.

Why: the code grade reads every source file of a class's hand-ins, as root. The walk is
:mod:`usar_replay.core.folder_walk`'s (the one ``usar batch`` and the ROS 1 build use: links
never followed, FIFOs and devices refused, sizes capped from ``lstat`` before a byte is read),
so what is graded is what is built. Past the walk, a C++ file that is over
:data:`MAX_SOURCE_BYTES`, holds a NUL byte (binary) or is not UTF-8 is left out and said, as a
*finding* of that team: never a crash, never a hang, and never a silent zero.

The folder given may be a team's folder, a repository or a catkin workspace: the package in it
is found as ``--ros1`` finds it (:func:`usar_replay.ros1.building.workspace.find_package`);
files outside the package (a report's PDF, instructions at the top) are the team's too.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path, PurePosixPath

from usar_replay.core.errors import NoPackage, UnusableSubmission
from usar_replay.core.folder_walk import Entry, shown, stream, walk
from usar_replay.ros1.building.workspace import Package, find_package

__all__ = [
    "CXX_SUFFIXES",
    "MAX_SOURCE_BYTES",
    "Source",
    "Submission",
    "read_submission",
    "read_text",
]

CXX_SUFFIXES = frozenset({".cpp", ".cc", ".cxx", ".c", ".h", ".hpp", ".hh", ".hxx"})
"""What counts as the package's C++ (sources and headers)."""
MAX_SOURCE_BYTES = 1024 * 1024
"""The largest C++ file read (1 MiB: ten times the largest hand-written one of a class)."""
SKIP_DIRS = frozenset({"build", "devel", "install", "log", "logs", ".git", "__pycache__"})
"""Folders never read (catkin's outputs, committed in many repositories; version control)."""


@dataclass(frozen=True, slots=True)
class Source:
    """One C++ file of the package: its path relative to the package, and its text."""

    rel: str
    """As :func:`~usar_replay.core.folder_walk.shown` writes it: a name that is not UTF-8, or
    holds a control character, escaped (``caf\\xe9.cpp``), so that every output can hold it
    and the copy a tool runs on has a name of its own."""
    text: str

    @property
    def lines(self) -> int:
        return self.text.count("\n") + (0 if self.text.endswith("\n") or not self.text else 1)


@dataclass(frozen=True, slots=True)
class Submission:
    """What the code grade reads of one team."""

    name: str
    """The team (its folder's name, or the package's)."""
    root: Path
    """The folder given (the team's folder, a repository, a workspace)."""
    package: Path
    """The catkin package folder in it."""
    package_name: str
    sources: tuple[Source, ...]
    """The package's readable C++ files, sorted by path."""
    files: tuple[str, ...]
    """Every file of the folder given, relative to :attr:`root` (``/``-separated, sorted)."""
    package_prefix: str
    """The package's path relative to :attr:`root` ('' when they are the same)."""
    findings: tuple[str, ...]
    """Files left out and why (one line each, safe to print)."""
    entries: tuple[Entry, ...] = ()

    def package_files(self) -> list[str]:
        """The package's files, relative to the package."""
        p = self.package_prefix
        if not p:
            return list(self.files)
        return [f[len(p) + 1 :] for f in self.files if f.startswith(p + "/")]

    def entry(self, rel: str) -> Entry | None:
        """The walked entry of ``rel`` (relative to :attr:`root`)."""
        for e in self.entries:
            if shown(e.rel) == rel:
                return e
        return None


def read_text(entry: Entry, max_bytes: int = MAX_SOURCE_BYTES) -> tuple[str | None, str]:
    """(text, '') of a walked file, or (None, why) for one over ``max_bytes``, binary or not
    UTF-8."""
    if entry.size > max_bytes:
        return None, f"{entry.size} bytes, over the {max_bytes} read"
    chunks: list[bytes] = []
    try:
        stream(entry, chunks.append)
    except UnusableSubmission as err:
        return None, str(err)
    data = b"".join(chunks)
    if b"\0" in data:
        return None, "binary (holds a NUL byte)"
    try:
        return data.decode("utf-8"), ""
    except UnicodeDecodeError as err:
        return None, f"not UTF-8 (byte {err.start})"


def read_submission(
    path: str | os.PathLike[str], name: str = "", *, need_package: bool = True
) -> Submission:
    """The team at ``path``: its package found as ``--ros1`` does, its files walked once.

    Raises a :class:`~usar_replay.core.errors.UsarError` (one line) when no package can be
    found or the folder breaks the walk's rules: the caller makes it that team's verdict.
    ``need_package`` False: a folder without ``package.xml`` is read as the package itself
    (the course template as some copies of it are handed out)."""
    root = Path(path)
    try:
        pkg = find_package(root)
    except NoPackage:
        if need_package or not root.is_dir():
            raise
        pkg = Package(root, root.name)
    findings: list[str] = []
    try:
        entries = walk(
            root, skip_dirs=SKIP_DIRS, what=f"the folder {shown(root.name)}", left_out=findings
        )
    except UnusableSubmission as err:
        raise UnusableSubmission(f"{shown(root.name)}: {err}") from None
    prefix = shown(pkg.path.relative_to(root).as_posix()) if pkg.path != root else ""
    prefix = "" if prefix == "." else prefix
    sources: list[Source] = []
    files: list[str] = []
    for e in entries:
        rel = shown(e.rel)
        files.append(rel)
        inside = not prefix or rel.startswith(prefix + "/")
        if not inside or PurePosixPath(rel).suffix.lower() not in CXX_SUFFIXES:
            continue
        rel_pkg = rel[len(prefix) + 1 :] if prefix else rel
        if rel_pkg.split("/")[0] == "doc":
            continue  # doxygen's output, not the team's sources
        if e.link is not None:
            findings.append(f"{shown(rel)}: a link, not read")
            continue
        text, why = read_text(e)
        if text is None:
            findings.append(f"{shown(rel)}: {why}; not graded")
            continue
        sources.append(Source(rel_pkg, text))
    return Submission(
        name=name or pkg.name,
        root=root,
        package=pkg.path,
        package_name=pkg.name,
        sources=tuple(sorted(sources, key=lambda s: s.rel)),
        files=tuple(sorted(files)),
        package_prefix=prefix,
        findings=tuple(findings),
        entries=tuple(entries),
    )
