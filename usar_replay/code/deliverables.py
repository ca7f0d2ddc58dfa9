"""The handout's files: a Doxyfile, ``doc/instructions.txt``.

Why apart from the HTML check (:mod:`usar_replay.code.docs_own`): these are named files the
handout asks for; whether their contents are right (do the instructions work?) is for the
grader. Instructions found elsewhere than ``doc/instructions.txt`` (an ``instructions.md`` at the
top, a README that says how to ``roslaunch``) earn part of the line: the team wrote them, in the
wrong place.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import PurePosixPath

from usar_replay.code.sources import Submission, read_text

__all__ = ["Deliverables", "deliverables"]

_INSTRUCTIONS = re.compile(r"instructions?[\w .-]*\.(txt|md|rst)$", re.I)
_README = re.compile(r"readme(\.(md|txt|rst))?$", re.I)
_RUNS = re.compile(r"\b(roslaunch|rosrun|catkin_make|catkin build)\b")


@dataclass(frozen=True, slots=True)
class Deliverables:
    doxyfile: str
    """The Doxyfile's path in the package ('' when none)."""
    instructions: str
    """``doc`` (``doc/instructions.txt``), ``elsewhere`` or ``none``."""
    instructions_at: str


def _is_doxyfile(name: str) -> bool:
    low = name.lower()
    return low in ("doxyfile", "doxyfile.in") or low.endswith(".doxyfile")


def deliverables(sub: Submission) -> Deliverables:
    files = sub.package_files()
    doxy = next((f for f in files if _is_doxyfile(PurePosixPath(f).name)), "")
    doc = next((f for f in files if f.lower() == "doc/instructions.txt"), "")
    if doc:
        return Deliverables(doxy, "doc", doc)
    for rel in sub.files:
        name = PurePosixPath(rel).name
        if _INSTRUCTIONS.search(name):
            return Deliverables(doxy, "elsewhere", rel)
    for rel in sub.files:
        if _README.match(PurePosixPath(rel).name):
            entry = sub.entry(rel)
            text, _ = read_text(entry, 256 * 1024) if entry and entry.link is None else (None, "")
            if text and _RUNS.search(text):
                return Deliverables(doxy, "elsewhere", rel)
    return Deliverables(doxy, "none", "")
