"""Unused functions, unread variables and lint findings, from cppcheck's XML.

Why cppcheck: on issue 45's 21 packages its ``unusedFunction`` check found, in one package, 27 real
unused getters and setters (the handout: "Get rid of unused code"), and its style checks are
about the code, not its whitespace (cpplint's findings were 84-99% whitespace). It runs on a copy
of the sources in :mod:`usar_replay.code.tools`' sandbox and limits, without
``--inline-suppr``: a team's ``// cppcheck-suppress`` comment hides nothing. Functions the
course template also defines are the template's, and are not counted unused.
"""

from __future__ import annotations

import tempfile
import xml.etree.ElementTree as ET
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from usar_replay.code.sources import Source
from usar_replay.code.tools import OUTPUT_CAP, ToolLimits, missing, run_tool, write_copy

__all__ = ["UNREAD", "UNUSED", "Finding", "Findings", "findings", "parse_xml"]

UNUSED = frozenset({"unusedFunction", "unusedPrivateFunction"})
"""cppcheck's ids of a function nobody calls."""
UNREAD = frozenset({"unreadVariable", "unusedVariable"})
"""cppcheck's ids of a variable nobody reads (``unusedStructMember`` is left out: on a test
package it missed reads through ``pair.second.x``)."""
_NOT_LINT = frozenset(
    {"missingInclude", "missingIncludeSystem", "checkersReport", "toomanyconfigs",
     "normalCheckLevelMaxBranches", "unmatchedSuppression", "noValidConfiguration",
     "syntaxError", "internalAstError", "unknownMacro"}
)  # fmt: skip
"""What cppcheck says about its own run, not about the code."""


@dataclass(frozen=True, slots=True)
class Finding:
    id: str
    severity: str
    file: str
    line: int
    symbol: str
    msg: str


@dataclass(frozen=True, slots=True)
class Findings:
    items: tuple[Finding, ...]
    problem: str = ""

    def of(self, ids: frozenset[str]) -> list[Finding]:
        return [f for f in self.items if f.id in ids]

    def lint(self) -> list[Finding]:
        """Style, warning, performance and portability findings that are not unused code."""
        return [
            f for f in self.items
            if f.id not in UNUSED | UNREAD | _NOT_LINT and f.severity != "information"
        ]  # fmt: skip


def parse_xml(text: str, template_names: frozenset[str] = frozenset()) -> list[Finding]:
    """cppcheck's ``--xml`` output as findings (paths relative to the copy's ``src/``), sorted;
    unused functions that ``template_names`` holds left out."""
    try:
        root = ET.fromstring(text)
    except ET.ParseError:
        return []
    out: set[Finding] = set()
    for err in root.iter("error"):
        loc = err.find("location")
        symbol = (err.findtext("symbol") or "").strip()
        if err.get("id") in UNUSED and symbol.split("::")[-1] in template_names:
            continue
        file = loc.get("file", "") if loc is not None else ""
        out.add(
            Finding(
                err.get("id", ""),
                err.get("severity", ""),
                file[4:] if file.startswith("src/") else file,
                int(loc.get("line", "0")) if loc is not None else 0,
                symbol,
                err.get("msg", ""),
            )
        )
    return sorted(out, key=lambda f: (f.file, f.line, f.id, f.symbol))


def findings(
    sources: Iterable[Source],
    template_names: frozenset[str] = frozenset(),
    limits: ToolLimits | None = None,
) -> Findings:
    """cppcheck's findings on ``sources`` (the package's ``include/`` on its include path)."""
    gone = missing("cppcheck")
    if gone:
        return Findings((), gone)
    srcs = list(sources)
    with tempfile.TemporaryDirectory(prefix="usar-cppcheck-") as tmp:
        work = Path(tmp)
        write_copy([("src/" + s.rel, s.text) for s in srcs], work)
        (work / "src").mkdir(exist_ok=True)
        argv = ["cppcheck", "--enable=style,unusedFunction", "--xml", "--quiet",
                "--std=c++14", "--language=c++", "-j1", "-Isrc/include", "src"]  # fmt: skip
        ran = run_tool(argv, work, limits)
        if ran.limit:
            return Findings((), f"cppcheck exceeded {ran.limit}")
        if ran.code != 0:
            return Findings((), f"cppcheck failed (exit {ran.code})")
        if ran.cut:  # a cut report would read as fewer findings: the team's files made it
            return Findings((), f"cppcheck exceeded its report's size ({OUTPUT_CAP} bytes)")
        # cppcheck writes a name's backslash (an escaped byte: ``caf\\xe9.cpp``) as ``/``
        names = {s.rel.replace("\\", "/"): s.rel for s in srcs}
        found = [
            Finding(f.id, f.severity, names.get(f.file, f.file), f.line, f.symbol, f.msg)
            for f in parse_xml(ran.errors, template_names)
        ]
        return Findings(tuple(sorted(found, key=lambda f: (f.file, f.line, f.id, f.symbol))))
