"""The class on one HTML page: a row per team, its points per rubric question, how it was started,
its verdict, and links to each run's page.

Why a page of its own: ``summary.txt`` fits 100 columns and so shows a world's total only; an
instructor checking a class against the demos they watched wants the course's questions
(section 9 of the handout: targets reached, markers detected, properly broadcast, follower
visits, time) side by side, how each team was started (the instructions' line, so a wrong start
is seen at a glance), and one click to the run's evidence. Everything comes from the runs'
``.grade.json`` files (:mod:`usar_replay.batch.classreport`'s :class:`ClassGrades`), so the
page of a resumed batch is the page of a batch run in one go.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from usar_replay import __version__
from usar_replay.batch.classreport import OUTCOME_WORDS, ClassGrades, start_text
from usar_replay.core.safe_text import html_text

__all__ = ["QUESTIONS", "class_page", "question_of"]

QUESTIONS = (
    ("targets", "targets reached"),
    ("detected", "markers detected"),
    ("broadcast", "properly broadcast"),
    ("follower", "follower visits, home"),
    ("time", "time"),
    ("other", "other lines"),
)
"""The handout's section-9 questions, as the page's columns (id, heading)."""


def question_of(check_id: str) -> str:
    """Which of :data:`QUESTIONS` a rubric line answers (by its id's shape)."""
    if check_id.startswith("explorer.target"):
        return "targets"
    if check_id.endswith(".detected"):
        return "detected"
    if check_id.endswith(".broadcast") or check_id.startswith("marker_frame."):
        return "broadcast"
    if check_id.startswith("follower.") or check_id == "explorer.home_before_follower":
        return "follower"
    if check_id == "time_limit":
        return "time"
    return "other"


_STYLE = """
body{font-family:system-ui,sans-serif;margin:1.5em;color:#222}
table{border-collapse:collapse;font-size:.92em} td,th{border:1px solid #ccc;padding:.25em .5em}
th{background:#f2f2f2;text-align:left} td.num{text-align:right;font-variant-numeric:tabular-nums}
.pass{color:#080;font-weight:600} .fail{color:#b00;font-weight:600} .muted{color:#666}
td.start{font-family:ui-monospace,monospace;font-size:.85em;max-width:34em}
""".strip()


def _points(checks: list[dict[str, Any]], question: str) -> tuple[float, float]:
    got = full = 0.0
    for c in checks:
        if question_of(str(c.get("id", ""))) == question:
            got += float(c.get("points", 0.0))
            full += float(c.get("max_points", 0.0))
    return got, full


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}" + ("" if n == 1 else "s")


def _num(x: float) -> str:
    return f"{x:.4g}"


def _code_cell(grades: ClassGrades, team: str) -> str:
    """The team's code grade (``usar batch --code``), and the teams its code is similar to,
    linking the page of their passages side by side (``code.html``, beside this page)."""
    c = grades.code.get(team)
    if c is None:
        return "<td class='muted'>no package</td>"
    text = f"{_num(c.points)}/{_num(c.max_points)}"
    if c.similar:
        text += ("<br><a href='code.html'>similar to "
                 + html_text(", ".join(c.similar)) + "</a>")  # fmt: skip
    return f"<td class='num'>{text}</td>"


def class_page(grades: ClassGrades, link: Callable[[str, str], str | None]) -> str:
    """The page (see the module doc); ``link(team, world)`` is a run page's address relative to
    the page, or None where there is none."""
    e = html_text  # every string, the team's above all: controls escaped, then HTML's
    used = [
        (q, title)
        for q, title in QUESTIONS
        if any(
            question_of(str(c.get("id", ""))) == q
            for cell in grades.cells.values()
            for c in cell.grade.get("checks", [])
        )
    ]
    head = ["team", "world", *(t for _, t in used), "points", "verdict", "started as"]
    if grades.code:
        head.append("code")
    rows = ["<tr>" + "".join(f"<th>{e(h)}</th>" for h in head) + "</tr>"]
    for team in grades.teams:
        for k, world in enumerate(grades.worlds):
            cell = grades.cells[(team, world)]
            checks = list(cell.grade.get("checks", []))
            href = link(team, world)
            world_cell = f"<a href='{e(href)}'>{e(world)}</a>" if href else e(world)
            cols = []
            for q, _ in used:
                got, full = _points(checks, q)
                cols.append(f"<td class='num'>{_num(got)}/{_num(full)}</td>" if full else "<td>")
            ok = cell.graded and cell.outcome == "done"  # the run finished: its points say more
            outcome = cell.outcome if cell.graded else "not graded"
            why = grades.problems.get(team) or str(cell.grade.get("outcome_reason", ""))
            word = OUTCOME_WORDS.get(cell.outcome, "")
            verdict = f"<span class='{'pass' if ok else 'fail'}'>{e(outcome)}</span>"
            if why and cell.outcome != "done":
                verdict += f"<br><span class='muted'>{e(why.strip().splitlines()[-1][:300])}</span>"
            elif word:
                verdict += f" <span class='muted'>{e(word)}</span>"
            start = start_text(grades, team) if k == 0 else ""
            rows.append(
                f"<tr><td>{e(team) if k == 0 else ''}</td><td>{world_cell}</td>{''.join(cols)}"
                f"<td class='num'>{_num(cell.points)}/{_num(cell.max_points)}</td>"
                f"<td>{verdict}</td><td class='start'>{e(start)}</td>"
                + (_code_cell(grades, team) if grades.code and k == 0 else
                   "<td></td>" if grades.code else "")
                + "</tr>"
            )  # fmt: skip
    totals = [grades.total(t) for t in grades.teams]
    full_marks = sum(1 for got, full in totals if full > 0 and got >= full)
    body = (
        f"<h1>The class: {_count(len(grades.teams), 'team')} on "
        f"{_count(len(grades.worlds), 'world')}</h1>"
        f"<p>{full_marks}/{len(grades.teams)} teams have full marks. A world's name links to "
        "its run's page (map, rubric with evidence, detection frames).</p>"
        f"<table>{''.join(rows)}</table>"
    )
    return (
        "<!DOCTYPE html>\n<html lang='en'><head><meta charset='utf-8'>"
        f"<title>usar batch: the class</title><style>{_STYLE}</style></head>"
        f"<body>{body}<p class='muted'>usar-replay {e(__version__)}</p></body></html>\n"
    )
