"""The code grades for people (a table of 100 columns) and for programs (JSON, CSV).

Why versioned and sorted: the JSON (``usar-code/1``) and CSV are read by other programs (a
spreadsheet, Gradescope's uploader), so their shape is documented (docs/code-rubric.md) and
every list is sorted: the same inputs give the same bytes, with no clock in them.
"""

from __future__ import annotations

import csv
import io
import json
import textwrap
from collections.abc import Sequence
from dataclasses import asdict
from typing import Any

from usar_replay.code.grade import PackageGrade
from usar_replay.code.similarity import Pair
from usar_replay.core.safe_text import csv_row, json_data, safe_line

__all__ = ["FORMAT", "to_csv", "to_json", "to_text"]

FORMAT = "usar-code/1"
WIDTH = 100


def _num(x: float | None) -> str:
    return "" if x is None else f"{x:.4g}"


def package_json(g: PackageGrade) -> dict[str, Any]:
    return {
        "team": g.team,
        "package": g.package,
        "path": g.path,
        "verdict": g.verdict,
        "points": g.points,
        "max_points": g.max_points,
        "lines": [
            {
                "id": s.line.id,
                "title": s.line.title,
                "points": s.points,
                "max_points": s.line.points,
                "measured": s.measured,
                "threshold": s.line.threshold,
                "source": s.line.source,
                "evidence": s.evidence,
                "note": s.note,
            }
            for s in g.lines
        ],
        "metrics": g.metrics,
        "evidence": g.evidence,
        "report": asdict(g.report) if g.report is not None else None,
        "findings": list(g.findings),
        "for_grader": list(g.grader),
    }


def to_json(
    grades: Sequence[PackageGrade],
    similar: Sequence[Pair],
    *,
    rubric: str,
    template: str | None,
    threshold: float,
) -> str:
    """The ``usar-code/1`` document (docs/code-rubric.md); every string's controls escaped
    (:func:`~usar_replay.core.safe_text.json_data`): team names, paths, evidence are the
    team's."""
    doc = {
        "format": FORMAT,
        "rubric": rubric,
        "template": template,
        "packages": [package_json(g) for g in sorted(grades, key=lambda g: g.team)],
        "similar_threshold": threshold,
        "similar": [
            {"a": p.a, "b": p.b, "score": p.score, "passages": [asdict(x) for x in p.passages]}
            for p in similar
        ],
    }
    return json.dumps(json_data(doc), indent=1, sort_keys=True, ensure_ascii=False) + "\n"


def to_csv(grades: Sequence[PackageGrade], similar: Sequence[Pair]) -> str:
    """One row per team: points, maximum, each line's points, the report's flags, and the
    teams it is similar to; every cell through :func:`~usar_replay.core.safe_text.csv_row`
    (a team folder named ``=HYPERLINK(...)`` is text in a spreadsheet, not a link)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    ids = [s.line.id for s in grades[0].lines] if grades else []
    w.writerow(csv_row(["format", "team", "package", "verdict", "points", "max_points", *ids,
                        "report_pages", "similar_to"]))  # fmt: skip
    for g in sorted(grades, key=lambda g: g.team):
        by_id = {s.line.id: s.points for s in g.lines}
        close = sorted(
            {f"{p.b if p.a == g.team else p.a} ({p.score:.2f})" for p in similar
             if g.team in (p.a, p.b)}
        )  # fmt: skip
        w.writerow(csv_row([FORMAT, g.team, g.package, g.verdict, _num(g.points),
                            _num(g.max_points), *(_num(by_id.get(i)) for i in ids),
                            "" if g.report is None or g.report.pages is None else g.report.pages,
                            "; ".join(close)]))  # fmt: skip
    return buf.getvalue()


def _report_line(g: PackageGrade) -> str:
    r = g.report
    if r is None or r.file is None:
        return "report: none found" + (f" ({r.problems[0]})" if r and r.problems else "")
    bits = [f"report: {r.file}", f"{r.pages} pages"]
    if r.missing_sections:
        bits.append("no " + "/".join(r.missing_sections))
    if r.cpp_code:
        bits.append(f"C++ code ({r.cpp_where})")
    if r.spelling_per_page is not None:
        bits.append(f"{r.spelling_per_page:g} unknown words a page")
    return ", ".join(bits)


def _cut(text: str) -> str:
    text = safe_line(text)
    return text if len(text) <= WIDTH else text[: WIDTH - 3] + "..."


def to_text(grades: Sequence[PackageGrade], similar: Sequence[Pair], threshold: float) -> str:
    """The table people read: per team its lines, its findings and report flags, then the
    similar pairs, each line at most 100 columns."""
    out: list[str] = []
    for g in sorted(grades, key=lambda g: g.team):
        out.append(_cut(f"{g.team} ({g.package or 'no package'}): {_num(g.points)}/"
                        f"{_num(g.max_points)} points" + ("" if g.verdict == "graded"
                                                         else f", {g.verdict}")))  # fmt: skip
        if g.verdict != "graded":  # every line 0 for the one reason below
            out += [_cut(f"  finding: {f}") for f in g.findings]
            continue
        for s in g.lines:
            pts = "  -  " if s.points is None else f"{s.points:5.4g}"
            shown = "" if s.measured is None else f" = {s.measured}"
            tail = s.evidence or s.note
            if s.measured is None and s.note and s.evidence:  # why there is no value, and where
                tail = f"{s.note}: {s.evidence}"
            out.append(_cut(f"  {pts}/{s.line.points:<4g} {s.line.id}{shown}  {tail}"))
        for f in g.findings:
            out.append(_cut(f"  finding: {f}"))
        out.append(_cut("  " + _report_line(g)))
    if grades and grades[0].grader:
        said = "for the grader (not scored): " + "; ".join(grades[0].grader)
        out += textwrap.wrap(safe_line(said), WIDTH, subsequent_indent="  ")
    if similar:
        out.append(_cut(f"similar pairs (score >= {threshold:g}, for a person to review):"))
        for p in similar:
            out.append(_cut(f"  {p.score:.2f}  {p.a} ~ {p.b}"))
    elif len(grades) > 1:
        out.append(f"no pair of teams scores {threshold:g} or more")
    return "\n".join(out) + "\n"
