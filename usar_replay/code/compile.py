"""Does the package compile, and without warnings? A syntax-only build of each C++ file.

Why the underlay: a course package includes ``fiducial_msgs/FiducialTransformArray.h``, which
Debian does not have; usar's underlay (``fiducial_msgs`` and the stand-ins, the course machine
usar builds the demo on) does, so its include folder is on the path (:func:`message_includes`,
built once if no run built it), and ``compiles`` is measured on every package that builds for
the demo (issue 51: every real package stopped at that header). A package whose own files do
not compile (a header opening a comment it never closes) is ``compiles = false`` with the
compiler's first error in the note, even where a header is also missing.

Why syntax-only and not catkin_make: a catkin build costs ~15 s of wall time and ~45 s of CPU
a package, past the code grade's 5 s budget, and its warnings are the compiler's anyway. Each
translation unit is checked with ``g++ -fsyntax-only -Wall -Wextra`` (the warnings a course
machine's ``catkin_make`` would show with them on), the package's ``include/`` and Debian's
ROS headers on the include path, and usar's built messages (``fiducial_msgs``, which Debian
lacks) when the ROS 1 build has made them. A header that is nowhere (a package Debian does not
have) leaves the answer ``None``, said, rather than a false "does not compile".

In ``usar batch --code`` the package is built anyway, by the demo's catkin_make (with the same
``-Wall -Wextra``: :data:`usar_replay.ros1.building.workspace.WARNING_FLAGS`), so
:func:`from_build` reads that build's output the same way instead: the compiler's lines about
the package's own files, nothing measured twice.
"""

from __future__ import annotations

import contextvars
import posixpath
import re
import tempfile
from collections.abc import Iterable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path, PurePosixPath

from usar_replay.code.sources import Source
from usar_replay.code.tools import ToolLimits, missing, run_tool, write_copy

__all__ = [
    "Compiled",
    "Diagnostic",
    "compile_check",
    "diagnostics",
    "from_build",
    "message_includes",
    "parse_output",
]

_UNITS = frozenset({".cpp", ".cc", ".cxx"})
_DIAG = (
    r"^{root}/(?P<file>[^:\n]+):(?P<line>\d+):\d+: "
    r"(?P<kind>warning|error|fatal error): (?P<msg>.*)$"
)
"""gcc's and clang's line about a file under ``root`` (a regular expression's text)."""
_CMAKE_ERROR = r"^CMake Error at (?:{root}/|{name}/)(?P<file>[^:\n]+):(?P<line>\d+)"
"""CMake's error in one of the package's files (named from the workspace's ``src/``)."""
_EVIDENCE = 4
"""``file:line`` places a build's evidence names."""
_GXX = ToolLimits(wall_s=90.0, cpu_s=60)
"""A unit with roscpp's headers takes g++ ~4 s of CPU; on a machine busy with a class's runs
its wall time was over 30 s (the tools' default), which would score a clean package 0."""
_ERROR_CHARS = 160
"""Of the compiler's first error, what the note keeps."""
_NO_HEADER = re.compile(r"fatal error: ([\w/.+-]+): No such file or directory")


@dataclass(frozen=True, slots=True)
class Compiled:
    compiles: bool | None
    warnings: int
    where: str
    """``file:line`` of the first error, else of the first warning ('' when clean); of a
    build's (:func:`from_build`), the first few, ``; `` between them."""
    problem: str = ""
    note: str = ""
    """How it was measured, when not by :func:`compile_check` (the line's note)."""

    @property
    def clean(self) -> bool | None:
        return None if self.compiles is None else self.compiles and self.warnings == 0


@dataclass(frozen=True, slots=True)
class Diagnostic:
    """A compiler's line about one of the package's files."""

    file: str
    """Relative to the package's folder (``src/explorer.cpp``)."""
    line: int
    kind: str
    """``warning``, ``error`` or ``fatal error``."""
    message: str

    @property
    def where(self) -> str:
        return f"{self.file}:{self.line}"


def diagnostics(output: str, root: str = "src") -> list[Diagnostic]:
    """The compiler's warnings and errors in ``output`` about files under the folder ``root``
    (as the compiler named it: a system header, or a header generated elsewhere, is not the
    package's), in the order printed."""
    pattern = re.compile(_DIAG.format(root=re.escape(root.rstrip("/"))), re.MULTILINE)
    return [
        Diagnostic(posixpath.normpath(m["file"]), int(m["line"]), m["kind"], m["msg"])
        for m in pattern.finditer(output)
    ]


def parse_output(output: str) -> tuple[int, int, str, str]:
    """(errors, warnings, first error's or warning's ``file:line``, a missing header or '')."""
    errors = warnings = 0
    first_error = first_warning = ""
    for d in diagnostics(output):
        where = d.where
        if d.kind == "warning":
            warnings += 1
            first_warning = first_warning or where
        else:
            errors += 1
            first_error = first_error or where
    header = _NO_HEADER.search(output)
    return errors, warnings, first_error or first_warning, header.group(1) if header else ""


def _places(found: Iterable[tuple[str, int]]) -> str:
    """The first few ``file:line`` of ``found`` in file and line order (a parallel make prints
    its units' lines in any order; the evidence is the same whichever came first)."""
    return "; ".join(f"{f}:{n}" for f, n in sorted(set(found))[:_EVIDENCE])


def from_build(output: str, root: str, failed: bool, flags: Sequence[str]) -> Compiled:
    """The package's catkin_make, read as :func:`compile_check` reads g++: ``output`` as it
    printed it, ``root`` the package's folder as it saw it, ``failed`` whether it failed,
    ``flags`` the warning flags it was given. A build that succeeded compiles, clean when no
    warning names a file of the package (under ``root``); one that failed does not, with the
    places of its errors (the compiler's, else CMake's in the package's files)."""
    found = diagnostics(output, root)
    warnings = [d for d in found if d.kind == "warning"]
    how = (
        f"the demo's catkin_make ({' '.join(flags)} added)"
        if flags
        else "the demo's catkin_make, its own flags (its CMake files ask for -Werror)"
    )
    if not failed:
        return Compiled(True, len(warnings), _places((d.file, d.line) for d in warnings), note=how)
    errors = [(d.file, d.line) for d in found if d.kind != "warning"]
    if not errors:
        name = re.escape(PurePosixPath(root).name)
        cmake = re.compile(_CMAKE_ERROR.format(root=re.escape(root), name=name), re.MULTILINE)
        errors = [(m["file"], int(m["line"])) for m in cmake.finditer(output)]
    return Compiled(False, len(warnings), _places(errors), note=f"{how} failed")


def message_includes() -> list[Path]:
    """The include folder of usar's underlay (``fiducial_msgs``' generated headers, and the
    stand-ins' packages: :mod:`usar_replay.ros1.building.standins`), the course machine usar
    builds the demo on: built here once if no run has built it yet (cached, the batch's own
    entry: :func:`usar_replay.ros1.building.workspace.underlay`), in the sandbox when there
    is one. ``[]`` where it cannot be built (no ROS 1 here): a header of it is then "not
    found here", said, never a false "does not compile"."""
    from usar_replay.core.errors import UsarError
    from usar_replay.ros1.building.workspace import underlay

    try:
        ws = underlay(fixed=True)
    except (UsarError, OSError):
        return []
    include = ws / "devel" / "include"
    return [include] if (include / "fiducial_msgs").is_dir() else []


def compile_check(
    sources: Iterable[Source],
    includes: Iterable[Path] = (),
    limits: ToolLimits | None = None,
    jobs: int = 2,
) -> Compiled:
    """The syntax-only build of every translation unit of ``sources`` (see the docstring)."""
    gone = missing("g++")
    if gone:
        return Compiled(None, 0, "", gone)
    srcs = list(sources)
    units = [s.rel for s in srcs if PurePosixPath(s.rel).suffix.lower() in _UNITS]
    extra = [str(p) for p in includes]
    with tempfile.TemporaryDirectory(prefix="usar-compile-") as tmp:
        work = Path(tmp)
        write_copy([("src/" + s.rel, s.text) for s in srcs], work)
        flags = ["-fsyntax-only", "-Wall", "-Wextra", "-std=c++14", "-Isrc/include",
                 *(f"-I{p}" for p in extra)]  # fmt: skip

        def one(unit: str) -> tuple[str, int, str]:
            ran = run_tool(["g++", *flags, f"src/{unit}"], work, limits or _GXX, ro_binds=extra)
            return ran.limit, ran.code, ran.errors

        # each unit in a copy of this thread's context: the team's budget holds in the pool
        runs = [(contextvars.copy_context(), u) for u in units]
        with ThreadPoolExecutor(max(1, jobs)) as pool:
            results = list(pool.map(lambda r: r[0].run(one, r[1]), runs))
    errors = warnings = 0
    where = first_error = ""
    for unit, (limit, code, output) in zip(units, results, strict=True):
        if limit:
            return Compiled(None, 0, "", f"g++ exceeded {limit} on {unit}")
        e, w, first, header = parse_output(output)
        said = [d for d in diagnostics(output) if d.kind != "warning"]
        if header and not [d for d in said if header not in d.message]:
            return Compiled(None, 0, "", f"{unit}: header {header} not found here")
        errors += e + (1 if code != 0 and not e else 0)
        warnings += w
        where = where or first
        if said and not first_error:  # the compiler's first error, as it said it
            first_error = f"{said[0].where}: {said[0].kind}: {said[0].message}"[:_ERROR_CHARS]
    return Compiled(errors == 0, warnings, where, note=first_error)
