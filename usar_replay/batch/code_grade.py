"""``usar batch --code``: the code submission graded beside the demo, for the class's table,
CSV, page and Gradescope.

Why a flag: the code grade costs about half a second a team and needs doxygen, cppcheck and
clang-format; a batch that only regrades demos should not pay for it or need them. With it,
every team folder that holds a catkin package is graded as ``usar code`` grades it
(:mod:`usar_replay.code.classgrade`: same discovery, rubric, template and similarity), and
``OUT/code.json`` (``usar-code/1``), ``OUT/code.csv`` and ``OUT/code.html`` (similar pairs'
passages side by side) are written. A team without a package (a Python mission) has no code
grade. Each team's :class:`CodeCell` is what the class's reports show: its own points and
maximum (a separate Gradescope test with its own ``max_score``), the rubric lines as text, and
the teams it is similar to (for a person; never points).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

__all__ = ["CODE_CSV", "CODE_HTML", "CODE_JSON", "CodeCell", "cells_from_json", "grade_code"]

CODE_JSON = "code.json"
CODE_CSV = "code.csv"
CODE_HTML = "code.html"


@dataclass(frozen=True, slots=True)
class CodeCell:
    points: float
    max_points: float
    lines: tuple[str, ...]
    """The rubric's lines for a person (``6/6 classes = 2  evidence``)."""
    similar: tuple[str, ...] = ()
    """``team (score)`` of each team listed as similar."""


def _line(raw: dict[str, Any]) -> str:
    pts = "-" if raw.get("points") is None else f"{float(raw['points']):.4g}"
    shown = "" if raw.get("measured") is None else f" = {raw['measured']}"
    tail = raw.get("evidence") or raw.get("note") or ""
    return f"{pts}/{float(raw.get('max_points', 0)):.4g} {raw.get('id', '')}{shown}  {tail}"


def cells_from_json(doc: dict[str, Any] | None) -> dict[str, CodeCell]:
    """Each team's cell from a ``usar-code/1`` document (``{}`` for anything else)."""
    if not doc or doc.get("format") != "usar-code/1":
        return {}
    similar: dict[str, list[str]] = {}
    for p in doc.get("similar", []):
        a, b, score = str(p.get("a")), str(p.get("b")), float(p.get("score", 0))
        similar.setdefault(a, []).append(f"{b} ({score:.2f})")
        similar.setdefault(b, []).append(f"{a} ({score:.2f})")
    out = {}
    for pkg in doc.get("packages", []):
        team = str(pkg.get("team", ""))
        out[team] = CodeCell(
            float(pkg.get("points", 0.0)),
            float(pkg.get("max_points", 0.0)),
            tuple(_line(x) for x in pkg.get("lines", [])),
            tuple(sorted(similar.get(team, []))),
        )
    return out


def grade_code(
    teams: Sequence[tuple[str, Path]], out_root: Path, template: str | None, jobs: int = 1
) -> dict[str, CodeCell]:
    """Grade the code of every team whose folder holds a package; write ``code.json``,
    ``code.csv`` and ``code.html`` into ``out_root``; each graded team's cell."""
    from usar_replay.code import classgrade, output, rubric
    from usar_replay.code import template as tmpl
    from usar_replay.code.html import pairs_html
    from usar_replay.core.outfiles import write_text
    from usar_replay.ros1.building.workspace import find_package

    def has_package(folder: Path) -> bool:
        try:
            find_package(folder)
        except Exception:  # noqa: BLE001 (no package, several, unreadable: no code grade)
            return False
        return True

    graded = [(team, f) for team, f in teams if f.is_dir() and has_package(f)]
    if not graded:
        return {}
    rub = rubric.default_rubric()
    base = tmpl.read_template(template) if template else tmpl.NO_TEMPLATE
    done = classgrade.grade_teams(graded, rub, base, jobs=jobs)
    doc = output.to_json(done.grades, done.similar, rubric=rub.name, template=template,
                         threshold=done.threshold)  # fmt: skip
    write_text(out_root / CODE_JSON, doc, overwrite=True)
    write_text(out_root / CODE_CSV, output.to_csv(done.grades, done.similar), overwrite=True)
    write_text(out_root / CODE_HTML, pairs_html(done.similar, done.threshold), overwrite=True)
    parsed: dict[str, Any] = json.loads(doc)
    return cells_from_json(parsed)
