"""Documentation coverage, classes and main()'s length, from doxygen's XML of the sources.

Why doxygen's XML and not its warnings: on issue 45's 21 packages doxygen's "undocumented" warning
count was 0 for a package with no comments at all (without ``EXTRACT_ALL`` it skips what is
undocumented; with it, it warns of nothing). Its XML lists every class and function with where
it is and its brief and detailed descriptions, so coverage is counted, not guessed: the share of
the package's own classes and functions (those the template also defines left out) that have a
description. The same parse gives the classes that have methods and main()'s body length (the
handout: "You must use OOP"; a main() as a thin driver).

doxygen runs with usar's Doxyfile (never the team's, which could name any path) on a copy of the
package's sources, in :mod:`usar_replay.code.tools`' sandbox and limits.
"""

from __future__ import annotations

import tempfile
import xml.etree.ElementTree as ET
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from usar_replay.code.sources import Source
from usar_replay.code.tools import ToolLimits, missing, run_tool, write_copy

__all__ = ["DOXYFILE", "Symbol", "Symbols", "parse_xml", "symbols"]

DOXYFILE = """\
INPUT = src
RECURSIVE = YES
FILE_PATTERNS = *.cpp *.cc *.cxx *.c *.h *.hpp *.hh *.hxx
GENERATE_HTML = NO
GENERATE_LATEX = NO
GENERATE_XML = YES
XML_OUTPUT = xml
XML_PROGRAMLISTING = NO
EXTRACT_ALL = YES
EXTRACT_PRIVATE = YES
EXTRACT_STATIC = YES
EXTRACT_ANON_NSPACES = YES
CASE_SENSE_NAMES = YES
ENABLE_PREPROCESSING = NO
QUIET = YES
WARNINGS = NO
WARN_IF_UNDOCUMENTED = NO
OUTPUT_DIRECTORY = out
HAVE_DOT = NO
NUM_PROC_THREADS = 1
"""
"""usar's Doxyfile: XML only, every symbol extracted (documented or not)."""


@dataclass(frozen=True, slots=True)
class Symbol:
    kind: str
    """``class`` (a class or struct) or ``function``."""
    name: str
    """Qualified (``ns::Class::method``)."""
    file: str
    """Where it is, relative to the package."""
    line: int
    documented: bool
    body_lines: int = 0
    """Lines of its body (functions with a body; 0 otherwise)."""
    methods: int = 0
    """Functions it declares (classes)."""


@dataclass(frozen=True, slots=True)
class Symbols:
    items: tuple[Symbol, ...]
    problem: str = ""
    """'' or why doxygen gave nothing (not installed, past a limit)."""


def _text(node: ET.Element | None) -> str:
    return "" if node is None else "".join(node.itertext()).strip()


def _documented(node: ET.Element) -> bool:
    return bool(_text(node.find("briefdescription")) or _text(node.find("detaileddescription")))


def _rel(path: str) -> str:
    return path[4:] if path.startswith("src/") else path


def parse_xml(folder: Path) -> list[Symbol]:
    """Every class (with its method count) and function doxygen's XML in ``folder`` lists,
    each once, sorted; ValueError when a file of it is not XML."""
    found: dict[str, Symbol] = {}
    for path in sorted(folder.glob("*.xml")):
        if path.name in ("index.xml", "Doxyfile.xml"):
            continue
        try:
            root = ET.parse(path).getroot()
        except ET.ParseError as err:  # skipped, its functions would be missing from the count
            raise ValueError(f"{path.name}: {err}") from None
        for comp in root.iter("compounddef"):
            kind = comp.get("kind", "")
            functions = []
            for mem in comp.iter("memberdef"):
                if mem.get("kind") != "function":
                    continue
                functions.append(mem)
                loc = mem.find("location")
                mid = mem.get("id", "")
                if loc is None or mid in found:
                    continue
                start, end = int(loc.get("bodystart", "-1")), int(loc.get("bodyend", "-1"))
                body = end - start + 1 if start > 0 and end >= start else 0
                found[mid] = Symbol(
                    "function",
                    _text(mem.find("qualifiedname")) or _text(mem.find("name")),
                    _rel(loc.get("bodyfile") or loc.get("file") or ""),
                    start if body else int(loc.get("line") or 0),
                    _documented(mem),
                    body,
                )
            if kind in ("class", "struct"):
                loc = comp.find("location")
                found[comp.get("id", "")] = Symbol(
                    "class",
                    _text(comp.find("compoundname")),
                    _rel(loc.get("file", "") if loc is not None else ""),
                    int(loc.get("line", "0") or 0) if loc is not None else 0,
                    _documented(comp),
                    methods=len(functions),
                )
    return sorted(found.values(), key=lambda s: (s.file, s.line, s.kind, s.name))


def symbols(sources: Iterable[Source], limits: ToolLimits | None = None) -> Symbols:
    """The classes and functions of ``sources`` as doxygen's XML lists them."""
    gone = missing("doxygen")
    if gone:
        return Symbols((), gone)
    with tempfile.TemporaryDirectory(prefix="usar-doxygen-") as tmp:
        work = Path(tmp)
        write_copy([("src/" + s.rel, s.text) for s in sources], work)
        (work / "src").mkdir(exist_ok=True)
        (work / "Doxyfile").write_text(DOXYFILE, encoding="utf-8")
        ran = run_tool(["doxygen", "Doxyfile"], work, limits)
        if ran.limit:
            return Symbols((), f"doxygen exceeded {ran.limit}")
        if ran.code != 0:
            return Symbols((), f"doxygen failed (exit {ran.code})")
        try:
            return Symbols(tuple(parse_xml(work / "out" / "xml")))
        except ValueError as err:
            return Symbols((), f"doxygen failed (exit 0, its XML unreadable: {err})")
