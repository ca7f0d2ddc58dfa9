"""A graded class for people and machines: the summary CSV and table, Gradescope's results.json.

Everything is read from the runs' ``<world>.grade.json`` files (format ``usar-batch-grade/1``),
so the summary of a resumed batch is the same as that of a batch run in one go. Teams and worlds
keep the batch's order (teams sorted by name, worlds as given); nothing depends on which run
finished first.
"""

from __future__ import annotations

import csv
import io
import json
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from usar_replay.batch.code_grade import CODE_JSON, CodeCell, cells_from_json
from usar_replay.batch.plan import GRADE_FORMAT, Plan, read_json
from usar_replay.core.safe_text import csv_row, json_data, safe_line

__all__ = [
    "CLASS_FILE",
    "CLASS_FORMAT",
    "class_json",
    "from_folder",
    "GRADESCOPE_VISIBILITY",
    "OUTCOME_MARKS",
    "ClassGrades",
    "collect",
    "gradescope_results",
    "start_text",
    "to_csv",
    "to_table",
]

OUTCOME_MARKS = {
    "done": "",
    "time_limit": "T",
    "max_sim_time": "S",
    "crashed": "C",
    "hung": "H",
    "out_of_memory": "M",
    "refused": "R",
    "build_failed": "B",
    "wall_limit": "W",
    "grade_limit": "G",
    "interrupted": "I",
    "no_mission": "N",
    "bad_submission": "U",
    "": "?",
}
"""The letter after a world's points in the table when the run did not end ``done``."""
OUTCOME_WORDS = {
    "done": "the mission finished",
    "time_limit": "stopped at the world's time limit",
    "max_sim_time": "stopped at the batch's --max-sim-time",
    "crashed": "the mission's code raised an exception",
    "hung": "a callback did not return in time (or the CPU-time limit)",
    "out_of_memory": "the mission ran out of memory",
    "refused": "the mission published something it may not",
    "build_failed": "the ROS 1 package did not build",
    "wall_limit": "the run took longer than its wall-clock limit",
    "grade_limit": "grading the log took longer than --grade-limit",
    "interrupted": "the run was interrupted",
    "no_mission": "no mission found in the submission",
    "bad_submission": "the submission's folder is unusable (a special file, a link out, too big)",
    "": "not run",
}
GRADESCOPE_VISIBILITY = ("visible", "hidden", "after_due_date", "after_published")


@dataclass(frozen=True, slots=True)
class Cell:
    """One (team, world) grade, or a missing one (``graded`` False: not run yet, or failed)."""

    graded: bool
    outcome: str
    points: float
    max_points: float
    grade: dict[str, Any]


@dataclass(frozen=True, slots=True)
class ClassGrades:
    teams: list[str]
    worlds: list[str]
    cells: dict[tuple[str, str], Cell]
    problems: dict[str, str]
    """Teams whose submission has no mission: why."""
    starts: dict[str, tuple[str, str]] = field(default_factory=dict)
    """A ROS 1 team's start as it ran (or as the plan read it) and where it was read."""
    code: dict[str, CodeCell] = field(default_factory=dict)
    """Each team's code grade (``usar batch --code``; empty without it)."""

    def total(self, team: str) -> tuple[float, float]:
        cells = [self.cells[(team, w)] for w in self.worlds]
        return sum(c.points for c in cells), sum(c.max_points for c in cells)


def collect(plan: Plan, max_points: dict[str, float]) -> ClassGrades:
    """Read every run's grade; ``max_points`` per world fills runs without one."""
    teams = [s.team for s in plan.submissions]
    worlds = [w.name for w in plan.worlds]
    problems = {s.team: s.problem for s in plan.submissions if s.problem}
    problem_outcomes = {s.team: s.problem_outcome for s in plan.submissions if s.problem}
    starts = {s.team: (s.start, s.start_source) for s in plan.submissions if s.start}
    cells: dict[tuple[str, str], Cell] = {}
    for team in teams:
        for world in worlds:
            full = max_points.get(world, 0.0)
            if team in problems:
                cells[(team, world)] = Cell(True, problem_outcomes[team], 0.0, full, {})
                continue
            g = read_json(plan.out_root / team / f"{world}.grade.json")
            if g is None or g.get("format") != GRADE_FORMAT:
                cells[(team, world)] = Cell(False, "", 0.0, full, {})
                continue
            cells[(team, world)] = Cell(
                True,
                str(g.get("outcome", "")),
                float(g.get("points", 0.0)),
                float(g.get("max_points", full)),
                g,
            )
            if g.get("start"):  # as it ran (the first world's)
                starts.setdefault(team, (str(g["start"]), str(g.get("start_source", ""))))
    return ClassGrades(teams, worlds, cells, problems, starts)


CLASS_FORMAT = "usar-batch-class/1"
CLASS_FILE = "class.json"


def class_json(grades: ClassGrades) -> str:
    """``OUT/class.json`` (format ``usar-batch-class/1``, docs/batch.md): the batch's teams and
    worlds in its order, each team's problem (outcome, reason) and start (commands, where read),
    so that ``usar report OUT`` rebuilds the class from the folder alone. Team text (a start,
    a problem) has its controls escaped (:func:`~usar_replay.core.safe_text.json_data`)."""
    outcomes = {t: grades.cells[(t, grades.worlds[0])].outcome for t in grades.problems}
    data = {
        "format": CLASS_FORMAT,
        "teams": grades.teams,
        "worlds": grades.worlds,
        "problems": {t: [outcomes.get(t, "no_mission"), why] for t, why in grades.problems.items()},
        "starts": {t: list(s) for t, s in grades.starts.items()},
    }
    return json.dumps(json_data(data), indent=2, sort_keys=True) + "\n"


def from_folder(out_root: Path) -> ClassGrades | None:
    """The class of a batch's output folder (its ``class.json`` and the runs' grades), or None
    when the folder is not one."""
    data = read_json(out_root / CLASS_FILE)
    if data is None or data.get("format") != CLASS_FORMAT:
        return None
    teams = [str(t) for t in data.get("teams", [])]
    worlds = [str(w) for w in data.get("worlds", [])]
    problems = {str(t): str(v[1]) for t, v in dict(data.get("problems", {})).items()}
    outcomes = {str(t): str(v[0]) for t, v in dict(data.get("problems", {})).items()}
    starts = {str(t): (str(v[0]), str(v[1])) for t, v in dict(data.get("starts", {})).items()}
    cells: dict[tuple[str, str], Cell] = {}
    for team in teams:
        for world in worlds:
            g = read_json(out_root / team / f"{world}.grade.json")
            if team in problems:
                cells[(team, world)] = Cell(True, outcomes[team], 0.0, 0.0, {})
            elif g is None or g.get("format") != GRADE_FORMAT:
                cells[(team, world)] = Cell(False, "", 0.0, 0.0, {})
            else:
                cells[(team, world)] = Cell(
                    True,
                    str(g.get("outcome", "")),
                    float(g.get("points", 0.0)),
                    float(g.get("max_points", 0.0)),
                    g,
                )
    code = cells_from_json(read_json(out_root / CODE_JSON))
    return ClassGrades(teams, worlds, cells, problems, starts, code)


def start_text(grades: ClassGrades, team: str) -> str:
    """``roslaunch P F; rosrun P N (doc/instructions.txt line 7)``, or '' (not a ROS 1 team).
    The team's text on one line, its controls escaped (:func:`safe_line`): a README's command
    may carry ESC sequences that would draw over ``summary.txt`` in a terminal."""
    how, source = grades.starts.get(team, ("", ""))
    if not how:
        return ""
    return safe_line(f"{how} ({source})" if source else how)


def _num(x: float) -> str:
    return f"{x:.4g}"


def to_csv(grades: ClassGrades) -> str:
    """One row per team: points per world, total, maximum, and the runs that did not end
    ``done`` (``world: outcome``). Every cell through
    :func:`~usar_replay.core.safe_text.csv_row` (controls escaped, formulas neutralised)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    code_cols = ["code", "code_max", "code_similar_to"] if grades.code else []
    w.writerow(csv_row(["team", *grades.worlds, "total", "max_total", "problems", "start",
                        "start_from", *code_cols]))  # fmt: skip
    for team in grades.teams:
        cells = [grades.cells[(team, wn)] for wn in grades.worlds]
        total, full = grades.total(team)
        notes = [
            f"{wn}: {c.outcome or 'not graded'}"
            for wn, c in zip(grades.worlds, cells, strict=True)
            if c.outcome != "done"
        ]
        if team in grades.problems:
            notes = [grades.problems[team]]
        w.writerow(
            csv_row([
                team,
                *(_num(c.points) if c.graded else "" for c in cells),
                _num(total),
                _num(full),
                "; ".join(notes),
                *grades.starts.get(team, ("", "")),
                *(_code_cells(grades, team) if grades.code else []),
            ])
        )  # fmt: skip
    return buf.getvalue()


def _code_cells(grades: ClassGrades, team: str) -> list[str]:
    c = grades.code.get(team)
    if c is None:
        return ["", "", ""]
    return [_num(c.points), _num(c.max_points), "; ".join(c.similar)]


def _code_table(grades: ClassGrades, width: int) -> list[str]:
    """The code grades under the demo's table: a line per team (docs/code-rubric.md)."""
    lines = ["code submission (usar code; the demo's total above does not include it):"]
    for team in grades.teams:
        c = grades.code.get(team)
        said = "no catkin package" if c is None else f"{_num(c.points)}/{_num(c.max_points)}"
        if c is not None and c.similar:
            said += "; similar to " + ", ".join(c.similar) + " (see code.html)"
        lines.append(_wrap(safe_line(f"  {team}: {said}"), width))
    return lines


def to_table(grades: ClassGrades, width: int = 100) -> str:
    """A table for people that fits ``width`` columns: points per world with a letter for a
    run that did not finish (legend below), the total; worlds that do not fit are left to the
    CSV and said so. Team text (names, problems, starts) has its controls escaped
    (:func:`safe_line`) before it is measured and wrapped; every line is checked again."""
    name_w = min(max([4, *(len(safe_line(t)) for t in grades.teams)]), 24)
    total_w = 13
    col_ws = [max(len(w), 6) for w in grades.worlds]
    room = width - name_w - total_w - 2
    shown = 0
    used = 0
    for cw in col_ws:
        if used + cw + 2 > room:
            break
        used += cw + 2
        shown += 1
    worlds = grades.worlds[:shown]
    head = "team".ljust(name_w) + "".join(
        "  " + w.rjust(cw) for w, cw in zip(worlds, col_ws, strict=False)
    )
    lines = [head + "  " + "total".rjust(total_w - 2)]
    marks_used: set[str] = set()
    for team in grades.teams:
        shown_team = safe_line(team)
        row = shown_team[: name_w - 1] + "~" if len(shown_team) > name_w else shown_team
        row = row.ljust(name_w)
        for w, cw in zip(worlds, col_ws, strict=False):
            c = grades.cells[(team, w)]
            mark = OUTCOME_MARKS.get(c.outcome, "?") if c.graded else "-"
            marks_used.add(mark)
            text = (_num(c.points) if c.graded else "") + (mark or " ")
            row += "  " + text.rjust(cw)
        total, full = grades.total(team)
        row += "  " + f"{_num(total)}/{_num(full)}".rjust(total_w - 2)
        lines.append(row.rstrip())
    legend = [
        f"{m} {OUTCOME_WORDS[o]}"
        for o, m in OUTCOME_MARKS.items()
        if m and m in marks_used and o != ""
    ]
    if "?" in marks_used:
        legend.append("? outcome unknown")
    if "-" in marks_used:
        legend.append("- not graded (see the batch's errors)")
    if legend:
        lines.append(_wrap("runs that did not finish: " + "; ".join(legend), width))
    if shown < len(grades.worlds):
        lines.append(f"({len(grades.worlds) - shown} more worlds in summary.csv)")
    for team in grades.teams:  # why a team has no run, and how each ROS 1 team was started
        if team in grades.problems:
            outcome = grades.cells[(team, grades.worlds[0])].outcome if grades.worlds else ""
            why = safe_line(f"{team}: {outcome or 'no_mission'}: {grades.problems[team]}")
            lines.append(_wrap(why, width))
    started = [(t, start_text(grades, t)) for t in grades.teams if start_text(grades, t)]
    if started:
        lines.append("started as:")
        lines += [_wrap(f"  {team}: {text}", width) for team, text in started]
    if grades.code:
        lines += _code_table(grades, width)
    return "\n".join(safe_line(line) for line in "\n".join(lines).split("\n"))


def _wrap(text: str, width: int) -> str:
    import textwrap

    return "\n".join(
        textwrap.wrap(text, width=width, subsequent_indent="  ", break_on_hyphens=False)
    )


def _check_lines(grade: dict[str, Any]) -> list[str]:
    out = []
    for c in grade.get("checks", []):
        verdict = "PASS" if c.get("passed") else "FAIL"
        pts = f"{_num(float(c.get('points', 0)))}/{_num(float(c.get('max_points', 0)))}"
        out.append(f"{verdict} {pts:>9}  {c.get('description', c.get('id', ''))}")
        if not c.get("passed") and c.get("measured"):
            out.append(f"               measured: {c['measured']}")
    return out


def gradescope_results(
    grades: ClassGrades,
    team: str,
    sources: dict[str, str],
    *,
    execution_time_s: float,
    visibility: str = "visible",
) -> dict[str, Any]:
    """Gradescope's autograder ``results.json`` for one team: a test per world (its points,
    ``passed`` at full marks, the rubric lines and the outcome as output) and, with ``usar
    batch --code``, a test for the code submission with its own ``max_score``; the top-level
    score is their sum."""
    tests = []
    for number, world in enumerate(grades.worlds, start=1):
        c = grades.cells[(team, world)]
        lines = [f"World {world} ({sources.get(world, world)})"]
        lines.append(f"Outcome: {c.outcome or 'not graded'} - {OUTCOME_WORDS.get(c.outcome, '')}")
        if team in grades.problems:
            lines.append(grades.problems[team])
        if start_text(grades, team):
            lines.append(f"Started with: {start_text(grades, team)}")
        reason = str(c.grade.get("outcome_reason", "")) if c.outcome != "done" else ""
        if reason:
            lines += ["", reason.rstrip()[-4000:]]
        if c.grade:
            lines += ["", *_check_lines(c.grade)]
        tests.append(
            {
                "name": f"{world}: the course rubric",
                "number": str(number),
                "score": round(c.points, 3),
                "max_score": round(c.max_points, 3),
                "status": "passed" if c.graded and c.points >= c.max_points > 0 else "failed",
                "output": "\n".join(lines),
                "visibility": visibility,
            }
        )
    total, full = grades.total(team)
    code = grades.code.get(team)
    if code is not None:  # its own test, its own max_score (docs/code-rubric.md)
        said = ["Code submission, graded by usar code (docs/code-rubric.md):", *code.lines]
        if code.similar:
            said.append("Similar to (for a person to review, never points): "
                        + ", ".join(code.similar))  # fmt: skip
        tests.append(
            {
                "name": "code submission: the code rubric",
                "number": str(len(tests) + 1),
                "score": round(code.points, 3),
                "max_score": round(code.max_points, 3),
                "status": "passed" if code.points >= code.max_points > 0 else "failed",
                "output": "\n".join(said),
                "visibility": visibility,
            }
        )
    failed = [w for w in grades.worlds if grades.cells[(team, w)].outcome != "done"]
    summary = f"usar batch: {_num(total)}/{_num(full)} points on {len(grades.worlds)} worlds"
    if failed:
        summary += f"; did not finish on: {', '.join(failed)}"
    if team in grades.problems:
        summary += f"\n{grades.problems[team]}"
    if start_text(grades, team):
        summary += f"\nStarted with: {start_text(grades, team)}"
    if code is not None:
        summary += f"\nusar code: {_num(code.points)}/{_num(code.max_points)} points"
        total, full = total + code.points, full + code.max_points
    return {
        "score": round(total, 3),
        "max_score": round(full, 3),
        "execution_time": round(execution_time_s),
        "output": summary,
        "visibility": visibility,
        "stdout_visibility": "hidden",
        "tests": tests,
    }


def gradescope_json(results: dict[str, Any]) -> str:
    """``results.json`` as Gradescope reads it: every string's controls escaped
    (:func:`~usar_replay.core.safe_text.json_data`), so that its output box shows a team's
    text and obeys none of it."""
    return json.dumps(json_data(results), indent=2, sort_keys=True) + "\n"


def team_wall_s(plan: Plan, team: str, worlds: Sequence[str]) -> float:
    """Sum of the team's recorded run times (what Gradescope shows as ``execution_time``)."""
    total = 0.0
    for w in worlds:
        rec = read_json(Path(plan.out_root) / team / f"{w}.run.json")
        if rec is not None:
            total += float(rec.get("wall_s", 0.0))
    return total
