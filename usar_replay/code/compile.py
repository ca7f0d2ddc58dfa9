"""Does the package compile, and without warnings? A syntax-only build of each C++ file.

Why syntax-only and not catkin_make: a catkin build costs ~15 s of wall time and ~45 s of CPU
a package, past the code grade's 5 s budget, and its warnings are the compiler's anyway. Each
translation unit is checked with ``g++ -fsyntax-only -Wall -Wextra`` (the warnings a course
machine's ``catkin_make`` would show with them on), the package's ``include/`` and Debian's
ROS headers on the include path, and usar's built messages (``fiducial_msgs``, which Debian
lacks) when the ROS 1 build has made them. A header that is nowhere (a package Debian does not
have) leaves the answer ``None``, said, rather than a false "does not compile".
"""

from __future__ import annotations

import re
import tempfile
from collections.abc import Iterable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path, PurePosixPath

from usar_replay.code.sources import Source
from usar_replay.code.tools import ToolLimits, missing, run_tool, write_copy

__all__ = ["Compiled", "compile_check", "message_includes", "parse_output"]

_UNITS = frozenset({".cpp", ".cc", ".cxx"})
_DIAG = re.compile(
    r"^src/(?P<file>[^:\n]+):(?P<line>\d+):\d+: (?P<kind>warning|error|fatal error): (?P<msg>.*)$",
    re.MULTILINE,
)
_NO_HEADER = re.compile(r"fatal error: ([\w/.+-]+): No such file or directory")


@dataclass(frozen=True, slots=True)
class Compiled:
    compiles: bool | None
    warnings: int
    where: str
    """``file:line`` of the first error, else of the first warning ('' when clean)."""
    problem: str = ""

    @property
    def clean(self) -> bool | None:
        return None if self.compiles is None else self.compiles and self.warnings == 0


def parse_output(output: str) -> tuple[int, int, str, str]:
    """(errors, warnings, first error's or warning's ``file:line``, a missing header or '')."""
    errors = warnings = 0
    first_error = first_warning = ""
    for m in _DIAG.finditer(output):
        where = f"{m['file']}:{m['line']}"
        if m["kind"] == "warning":
            warnings += 1
            first_warning = first_warning or where
        else:
            errors += 1
            first_error = first_error or where
    header = _NO_HEADER.search(output)
    return errors, warnings, first_error or first_warning, header.group(1) if header else ""


def message_includes() -> list[Path]:
    """usar's built message headers (``fiducial_msgs``), when the ROS 1 build has made its
    underlay here (never built for the code grade)."""
    from usar_replay.ros1.building.workspace import cache_root

    root = cache_root()
    found = sorted(root.glob("underlay-*/ws/devel/include")) if root.is_dir() else []
    return [p for p in found if (p / "fiducial_msgs").is_dir()][:1]


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
            ran = run_tool(["g++", *flags, f"src/{unit}"], work, limits, ro_binds=extra)
            return ran.limit, ran.code, ran.errors

        with ThreadPoolExecutor(max(1, jobs)) as pool:
            results = list(pool.map(one, units))
    errors = warnings = 0
    where = ""
    for unit, (limit, code, output) in zip(units, results, strict=True):
        if limit:
            return Compiled(None, 0, "", f"g++ exceeded {limit} on {unit}")
        e, w, first, header = parse_output(output)
        if header:
            return Compiled(None, 0, "", f"{unit}: header {header} not found here")
        errors += e + (1 if code != 0 and not e else 0)
        warnings += w
        where = where or first
    return Compiled(errors == 0, warnings, where)
