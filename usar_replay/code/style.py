"""Formatting against the course's style (clang-format, Google's), beyond indentation width.

Why not raw clang-format: on issue 45's 21 packages its changes were dominated by 4- vs 2-space
indents, which the course never asked about and which say nothing of the code. Here each file
is formatted with the shipped ``course.clang-format`` (Google C++ Style, the course's guide) at
the file's own indentation width (:func:`indent_width`), and the measure is the share of its
lines clang-format would change: braces, spacing, line length, pointer alignment, one statement
a line. It runs on a copy, in :mod:`usar_replay.code.tools`' sandbox and limits.
"""

from __future__ import annotations

import difflib
import tempfile
from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from usar_replay.code.sources import Source
from usar_replay.code.tools import ToolLimits, missing, run_tool, write_copy

__all__ = ["Style", "course_style", "indent_width", "style"]


@dataclass(frozen=True, slots=True)
class Style:
    changed_share: float | None
    """Share of the C++ lines clang-format changes (None: not measured, :attr:`problem`)."""
    changed_lines: int
    lines: int
    worst: str
    """``file:line`` of the first changed line of the file with the most changes."""
    problem: str = ""


def course_style(indent: int) -> str:
    """The shipped style as clang-format's inline ``--style`` value, at ``indent`` spaces."""
    text = resources.files("usar_replay.code").joinpath("course.clang-format").read_text()
    pairs = [
        line.split(":", 1) for line in text.splitlines()
        if line.strip() and not line.lstrip().startswith("#") and ":" in line
    ]  # fmt: skip
    keys = {k.strip(): v.strip() for k, v in pairs}
    keys["IndentWidth"] = str(indent)
    keys["ContinuationIndentWidth"] = str(2 * indent)
    return "{" + ", ".join(f"{k}: {v}" for k, v in keys.items()) + "}"


def indent_width(text: str) -> int:
    """The file's indentation step: the commonest increase of leading spaces from one line to
    the next (2 when the file says nothing)."""
    steps: Counter[int] = Counter()
    last = 0
    for line in text.expandtabs(4).splitlines():
        if not line.strip():
            continue
        lead = len(line) - len(line.lstrip(" "))
        if lead > last and lead - last in (2, 3, 4, 8):
            steps[lead - last] += 1
        last = lead
    return steps.most_common(1)[0][0] if steps else 2


def _changed(before: str, after: str) -> tuple[int, int]:
    """(lines of ``before`` that formatting changes, the first one's number)."""
    a, b = before.splitlines(), after.splitlines()
    count, first = 0, 0
    for tag, i1, i2, _, _ in difflib.SequenceMatcher(None, a, b, autojunk=False).get_opcodes():
        if tag in ("replace", "delete"):
            count += i2 - i1
            first = first or i1 + 1
        elif tag == "insert":
            count += 1
            first = first or i1 + 1
    return count, first


def style(sources: Iterable[Source], limits: ToolLimits | None = None) -> Style:
    """The share of ``sources``' lines clang-format changes (see the module's docstring)."""
    srcs = list(sources)
    gone = missing("clang-format")
    if gone:
        return Style(None, 0, 0, "", gone)
    total = sum(s.lines for s in srcs)
    by_indent: dict[int, list[Source]] = {}
    for s in srcs:
        by_indent.setdefault(indent_width(s.text), []).append(s)
    changed, worst, worst_n = 0, "", 0
    with tempfile.TemporaryDirectory(prefix="usar-format-") as tmp:
        work = Path(tmp)
        for indent, group in sorted(by_indent.items()):
            sub = work / f"i{indent}"
            write_copy([(s.rel, s.text) for s in group], sub)
            argv = ["clang-format", "-i", f"--style={course_style(indent)}"]
            argv += [s.rel for s in group]
            ran = run_tool(argv, sub, limits)
            if ran.limit or ran.code != 0:
                why = f"exceeded {ran.limit}" if ran.limit else f"failed (exit {ran.code})"
                return Style(None, 0, total, "", f"clang-format {why}")
            for s in group:
                after = (sub / s.rel).read_text(encoding="utf-8", errors="replace")
                n, first = _changed(s.text, after)
                changed += n
                if n > worst_n:
                    worst, worst_n = f"{s.rel}:{first}", n
    share = round(changed / total, 3) if total else 0.0
    return Style(share, changed, total, worst)
