"""One submission graded in place for Gradescope: ``/autograder/submission`` in,
``/autograder/results/results.json`` out, through the batch's own plan, engine and grades.

Why its own face: Gradescope runs one container per submission, with the student's files in a
folder of its own (no class folder around it) and a timeout that kills the container, not usar.
So the submission is read where it lies (:func:`~usar_replay.batch.plan.discover_team`: no link,
which a class folder refuses, and no copy), and the results file is written early and kept
true: a 0-point file that says grading started before the first run, rewritten after each
world with the worlds graded so far, and the batch's own ``results.json`` at the end. Each write
is atomic (:mod:`usar_replay.core.outfiles`), so a timeout at any moment leaves a whole file
with every world finished by then.

The file's format is Gradescope's autograder specification, as ``usar batch --gradescope``
writes it (docs/gradescope.md).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from usar_replay.batch.classreport import collect, gradescope_json, gradescope_results, team_wall_s
from usar_replay.batch.driver import GRADESCOPE_FILE, BatchSummary, grade_class, require_sandbox
from usar_replay.batch.engines import make_engine
from usar_replay.batch.plan import Plan, RunResult, World, discover_team, make_plan, read_json
from usar_replay.batch.run_one import max_points
from usar_replay.core.errors import UsageError
from usar_replay.core.limits import GRADESCOPE_LIMITS, RunLimits
from usar_replay.core.outfiles import write_text

__all__ = [
    "AUTOGRADER_ENV",
    "Autograder",
    "error_results",
    "grade_submission",
    "pending_results",
    "results_so_far",
    "write_results",
]

AUTOGRADER_ENV = "USAR_AUTOGRADER"
"""The autograder's root folder (default ``/autograder``): tests and other layouts set it."""
TEAM = "submission"
PENDING = "not graded yet: the autograder stopped before this world's run ended"


@dataclass(frozen=True, slots=True)
class Autograder:
    """Where Gradescope puts things: the submission, the results file."""

    submission: Path
    results: Path

    @classmethod
    def here(cls, submission: str | None = None, results: str | None = None) -> Autograder:
        """``--submission``/``--results`` when given, else under ``$USAR_AUTOGRADER`` (default
        ``/autograder``): ``submission/`` and ``results/results.json``."""
        root = Path(os.environ.get(AUTOGRADER_ENV) or "/autograder")
        return cls(
            Path(submission) if submission else root / "submission",
            Path(results) if results else root / "results" / "results.json",
        )


def write_results(path: Path, results: dict[str, Any]) -> None:
    """The results file, atomically (a reader sees the old file or the new one, whole)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    write_text(path, gradescope_json(results), overwrite=True)


def error_results(message: str) -> dict[str, Any]:
    """0 points and the one line that says why nothing was graded (the autograder's setup, not
    the student's code: an instructor reads it in the submission's output)."""
    return {
        "score": 0.0,
        "output": f"usar: error: {message}",
        "visibility": "visible",
        "stdout_visibility": "hidden",
        "tests": [],
    }


def pending_results(
    worlds: Sequence[World], full: dict[str, float], visibility: str
) -> dict[str, Any]:
    """The file written before the first run: 0 of the full points, a test per world."""
    tests = [
        {
            "name": f"{w.name}: the course rubric",
            "number": str(n),
            "score": 0.0,
            "max_score": round(full[w.name], 3),
            "status": "failed",
            "output": f"World {w.name} ({w.source})\n{PENDING}",
            "visibility": visibility,
        }
        for n, w in enumerate(worlds, start=1)
    ]
    return {
        "score": 0.0,
        "max_score": round(sum(full.values()), 3),
        "execution_time": 0,
        "output": _started(len(worlds), 0),
        "visibility": visibility,
        "stdout_visibility": "hidden",
        "tests": tests,
    }


def _started(worlds: int, done: int) -> str:
    return (
        f"usar gradescope: grading started; {done} of {worlds} worlds graded so far. If this is "
        "the last word, the autograder stopped before usar finished (its timeout): the worlds "
        "not graded score 0."
    )


def results_so_far(plan: Plan, full: dict[str, float], visibility: str) -> dict[str, Any]:
    """The results file with every world graded by now (from the runs' grade files, as the
    batch reads them) and the others pending at 0 points."""
    grades = collect(plan, full)
    team = plan.submissions[0].team
    sources = {w.name: w.source for w in plan.worlds}
    results = gradescope_results(
        grades,
        team,
        sources,
        execution_time_s=team_wall_s(plan, team, grades.worlds),
        visibility=visibility,
    )
    done = 0
    for test, world in zip(results["tests"], grades.worlds, strict=False):
        if grades.cells[(team, world)].graded:
            done += 1
        else:
            test["output"] = f"World {world} ({sources[world]})\n{PENDING}"
    results["output"] = _started(len(grades.worlds), done) + "\n" + results["output"]
    return results


def grade_submission(
    where: Autograder,
    worlds: Sequence[World],
    work: Path,
    *,
    settings_toml: str,
    thresholds_toml: str = "",
    limits: RunLimits = GRADESCOPE_LIMITS,
    sandbox: bool = True,
    visibility: str = "visible",
    quiet: bool = False,
    code: bool = False,
    code_template: str | None = None,
    on_write: Callable[[dict[str, Any]], None] | None = None,
) -> tuple[dict[str, Any], BatchSummary]:
    """Grade ``where.submission`` on ``worlds`` (its runs' files in ``work``, one run at a
    time) and keep ``where.results`` written: early, after each world, at the end. Returns the
    final results and the batch's summary; ``on_write`` sees every results file written."""
    sub_path = where.submission.resolve()
    out = work.resolve()
    if out == sub_path or out.is_relative_to(sub_path) or sub_path.is_relative_to(out):
        raise UsageError(
            f"--work {work}: the work folder and the submission must not contain each other"
        )

    def write(results: dict[str, Any]) -> None:
        write_results(where.results, results)
        if on_write is not None:
            on_write(results)

    full = {w.name: max_points(w.scenario_toml) for w in worlds}
    write(pending_results(worlds, full, visibility))
    if sandbox:
        require_sandbox()
    plan = make_plan(
        [discover_team(where.submission, TEAM)],
        worlds,
        out,
        settings_toml=settings_toml,
        thresholds_toml=thresholds_toml,
        limits=limits,
        sandbox=sandbox,
        submissions_root=where.submission,
    )

    def after_run(_r: RunResult) -> None:
        write(results_so_far(plan, full, visibility))

    summary = grade_class(
        plan,
        make_engine("local", 1),
        gradescope=True,
        visibility=visibility,
        quiet=quiet,
        code=code,
        code_template=code_template,
        on_result=after_run,
    )
    final = read_json(out / TEAM / GRADESCOPE_FILE)
    if final is None:  # the batch writes it; nothing else would
        raise UsageError(f"{out / TEAM / GRADESCOPE_FILE}: the batch wrote no results file")
    write(final)
    return final, summary
