"""The batch's words and numbers agree: the table's legend tells ``--max-sim-time`` from the
world's time limit, and the progress bar counts runs that did not finish and usar's errors as
the final lines do (it used to add both into one "failures" figure)."""

from __future__ import annotations

import io
import json
import re
from pathlib import Path

from usar_replay.batch.classreport import collect, to_table
from usar_replay.batch.driver import BatchSummary, _Progress
from usar_replay.batch.plan import GRADE_FORMAT, Plan, RunJob, RunResult, Submission, World


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
