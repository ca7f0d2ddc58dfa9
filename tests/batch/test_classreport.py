"""The batch's words and numbers agree: the table's legend tells ``--max-sim-time`` from the
world's time limit, and the progress bar counts runs that did not finish and usar's errors as
the final lines do (it used to add both into one "failures" figure)."""

from __future__ import annotations

import csv
import io
import json
import re
from pathlib import Path

from usar_replay.batch.classpage import class_page
from usar_replay.batch.classreport import (
    class_json,
    collect,
    gradescope_json,
    gradescope_results,
    to_csv,
    to_table,
)
from usar_replay.batch.code_grade import CodeCell
from usar_replay.batch.driver import BatchSummary, _Progress
from usar_replay.batch.plan import GRADE_FORMAT, Plan, RunJob, RunResult, Submission, World
from usar_replay.core.safe_text import safe


def _plan(tmp_path: Path, teams: list[str], worlds: list[str]) -> Plan:
    return Plan(
        tmp_path,
        [Submission(t, tmp_path, "", "", "") for t in teams],
        [World(w, "", w) for w in worlds],
    )


def test_the_legend_tells_max_sim_time_from_the_time_limit(tmp_path: Path) -> None:
    plan = _plan(tmp_path, ["alice", "bob"], ["w"])
    for team, outcome in (("alice", "max_sim_time"), ("bob", "time_limit")):
        (tmp_path / team).mkdir()
        grade = {"format": GRADE_FORMAT, "outcome": outcome, "points": 30.0, "max_points": 60.0}
        (tmp_path / team / "w.grade.json").write_text(json.dumps(grade))
    table = to_table(collect(plan, {"w": 60.0})).splitlines()
    assert table[1].split() == ["alice", "30S", "30/60"]
    assert table[2].split() == ["bob", "30T", "30/60"]
    legend = " ".join(" ".join(table[3:]).split())
    assert "S stopped at the batch's --max-sim-time" in legend
    assert "T stopped at the world's time limit" in legend


def test_the_bar_and_the_final_lines_count_alike(tmp_path: Path) -> None:
    plan = _plan(tmp_path, ["a", "b", "c", "d"], ["w"])
    plan.finished = [RunResult("d", "w", "finished", "time_limit", 10.0, 60.0)]
    job = RunJob("x", "w", "", "", "", "", "", {}, "", "", "", {})
    plan.jobs = [job] * 3
    results = [
        RunResult("a", "w", "graded", "done", 60.0, 60.0),
        RunResult("b", "w", "graded", "crashed", 0.0, 60.0),
        RunResult("c", "w", "error", error="disk full"),
    ]
    stream = io.StringIO()
    with _Progress(plan, quiet=False, stream=stream) as bar:
        for r in results:
            bar(r)
    final = BatchSummary(plan, results).lines()
    assert (bar.unfinished, bar.errors) == (2, 1)
    assert "did not finish 2, errors 1" in stream.getvalue()
    assert final[0].endswith("1 errors")
    did_not_finish = re.findall(r"[a-z ]+ (\d+)", final[1].split(": ", 1)[1])
    assert sum(map(int, did_not_finish)) == bar.unfinished


EVIL = '=HYPERLINK("https:\\\\evil.invalid","open report")'
ESC = "\x1b[2J\x1b[H\x9b31m\u202e\u2028"


def _no_controls(text: str, kept: str = "\n") -> None:
    bad = [ch for ch in text if safe(ch) != ch and ch not in kept]
    assert not bad, f"raw controls {bad!r} in {text[:200]!r}"


def test_team_text_is_text_in_every_class_output(tmp_path: Path) -> None:
    """Issue 50, findings 5 and 6: a start with ESC sequences, a problem quoting controls and
    names that begin with a formula reach summary.txt, summary.csv, class.json, class.html and
    results.json escaped for each medium."""
    plan = _plan(tmp_path, ["-cmd", "alice", "bob"], ["w"])
    plan.submissions[1] = Submission(
        "alice", tmp_path, "", "", "", start=f"rostopic pub -1 /n std_msgs/String 'data: {ESC}'",
        start_source=f"README.md line 3{ESC}",
    )  # fmt: skip
    plan.submissions[2] = Submission("bob", tmp_path, "", "", f"{EVIL}: bad{ESC}")
    for team in ("-cmd", "alice"):
        (tmp_path / team).mkdir()
        grade = {"format": GRADE_FORMAT, "outcome": "crashed", "points": 1.0, "max_points": 60.0,
                 "outcome_reason": f"Traceback\n{ESC}", "checks": [
                     {"id": "x", "passed": False, "points": 0, "max_points": 4,
                      "description": f"frame {ESC}", "measured": f"{EVIL}{ESC}"}]}  # fmt: skip
        (tmp_path / team / "w.grade.json").write_text(json.dumps(grade))
    grades = collect(plan, {"w": 60.0})
    grades.code["-cmd"] = CodeCell(1.0, 2.0, (f"line {ESC}",), (f"{EVIL} (0.90)",))
    table = to_table(grades)
    _no_controls(table)
    assert "alice: rostopic pub -1 /n std_msgs/String 'data: \\x1b[2J" in table
    assert all(len(line) <= 100 for line in table.splitlines())
    rows = list(csv.reader(io.StringIO(to_csv(grades))))
    _no_controls(to_csv(grades))
    cells = [c for row in rows for c in row]
    assert "'-cmd" in cells and not any(c.startswith(("=", "+", "@", "\t", "\r")) for c in cells)
    assert not any(c.startswith("-") and not re.fullmatch(r"-[\d.]+", c) for c in cells)
    assert any(c.startswith("'=HYPERLINK(") for c in cells)  # the problem, and the code cell
    for doc in (class_json(grades), *(
        gradescope_json(gradescope_results(grades, t, {}, execution_time_s=1.0))
        for t in grades.teams
    )):  # fmt: skip
        _no_controls(doc)
        _no_controls(json.dumps(json.loads(doc), ensure_ascii=False), kept="\n\t")
        strings = re.findall(r'"((?:[^"\\]|\\.)*)"', doc)
        assert all(safe(json.loads(f'"{s}"'), lines=True) == json.loads(f'"{s}"') for s in strings)
    page = class_page(grades, lambda _t, _w: None)
    _no_controls(page)
    assert "<a href" not in page.split("<table>", 1)[1].replace("<a href='code.html'>", "")
    assert "=HYPERLINK(&quot;https:" in page and "\\x1b[2J" in page
