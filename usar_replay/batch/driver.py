"""Grading a class end to end: plan the runs, execute the missing ones with a progress bar, write
the class summary and Gradescope's files. The ``usar batch`` command is a thin face over
:func:`grade_class`.

Progress (``rich``, on stderr): runs done / to do, runs whose mission did not finish and runs
usar could not record or grade (``errors``), counted as the final lines count them, elapsed
time and an ETA from the runs done in this invocation (runs finished before are counted apart,
so they do not skew the ETA), and a line per finished run above the bar. Without a terminal
only the per-run lines are printed.
"""

from __future__ import annotations

import os
import sys
import textwrap
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TextIO

from usar_replay.batch.classpage import class_page
from usar_replay.batch.classreport import (
    CLASS_FILE,
    class_json,
    collect,
    gradescope_json,
    gradescope_results,
    team_wall_s,
    to_csv,
    to_table,
)
from usar_replay.batch.engines import Engine
from usar_replay.batch.plan import (
    JobLimits,
    Plan,
    RunResult,
    discover,
    make_plan,
    make_worlds,
)
from usar_replay.batch.run_one import max_points
from usar_replay.core.errors import UsageError
from usar_replay.core.outfiles import write_text
from usar_replay.core.safe_text import safe_line
from usar_replay.world.world_key import WorldKey

__all__ = ["BatchSummary", "grade_class", "plan_class", "require_sandbox"]

SUMMARY_CSV = "summary.csv"
SUMMARY_TXT = "summary.txt"
CLASS_PAGE = "class.html"
GRADESCOPE_FILE = "results.json"


@dataclass(slots=True)
class BatchSummary:
    """What a batch did, for the final lines and the exit code."""

    plan: Plan
    results: list[RunResult] = field(default_factory=list)
    table: str = ""

    @property
    def errors(self) -> list[RunResult]:
        return [r for r in self.results if r.state == "error"]

    @property
    def interrupted(self) -> bool:
        return any(r.state == "interrupted" for r in self.results)

    def lines(self) -> list[str]:
        now = [r for r in self.results if r.state == "graded"]
        every = [*self.plan.finished, *self.plan.invalid, *now]
        outcomes = Counter(r.outcome for r in every if r.outcome != "done")
        text = (
            f"{self.plan.total} runs ({len(self.plan.submissions)} teams x "
            f"{len(self.plan.worlds)} worlds): {len(now)} graded now, "
            f"{len(self.plan.finished)} finished before, {len(self.errors)} errors"
        )
        out = [text]
        if outcomes:
            out.append(
                "runs that did not finish: "
                + ", ".join(f"{o.replace('_', ' ')} {n}" for o, n in sorted(outcomes.items()))
            )
        for r in self.errors:
            said = r.error.strip()
            first = safe_line(said.splitlines()[0]) if said else "unknown error"
            out += textwrap.wrap(
                f"error: {r.team} on {r.world}: {first} (it is redone next time)",
                100,
                subsequent_indent="  ",
                break_on_hyphens=False,
            )
        return out


def plan_class(
    submissions_dir: str | os.PathLike[str],
    out_dir: str | os.PathLike[str],
    *,
    seeds: Sequence[int] = (),
    scenarios: Sequence[str] = (),
    settings_toml: str,
    thresholds_toml: str = "",
    limits: JobLimits | None = None,
    world_key: WorldKey | None = None,
) -> Plan:
    """The plan of a batch: teams, worlds (seeded ones keyed by ``world_key``: hidden worlds),
    and which runs still need doing."""
    out, subs_root = Path(out_dir).resolve(), Path(submissions_dir).resolve()
    if out == subs_root or out.is_relative_to(subs_root) or subs_root.is_relative_to(out):
        raise UsageError(
            f"-o {out_dir}: the output folder and {submissions_dir} must not contain each other; "
            "choose an output folder elsewhere"
        )
    if (limits or JobLimits()).sandbox:
        require_sandbox()
    subs = discover(submissions_dir)
    worlds = make_worlds(seeds, scenarios, world_key)
    return make_plan(
        subs,
        worlds,
        out_dir,
        settings_toml=settings_toml,
        thresholds_toml=thresholds_toml,
        limits=limits,
        submissions_root=submissions_dir,
    )


def require_sandbox() -> None:
    """Refuse to grade untrusted code without the kernel sandbox
    (sandbox.kernel_sandbox): a :class:`UsageError` (exit 2) that says how to get it, or to
    go without on purpose."""
    from usar_replay.sandbox.confinement import refusal
    from usar_replay.sandbox.kernel_sandbox import bwrap_available

    ok, why = bwrap_available()
    if not ok:
        raise UsageError(refusal(why, "usar batch"))


class _Progress:
    """The bar and the per-run lines (rich, on stderr)."""

    def __init__(self, plan: Plan, quiet: bool, stream: TextIO) -> None:
        from rich.console import Console
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            TextColumn,
            TimeElapsedColumn,
            TimeRemainingColumn,
        )

        self.console = Console(file=stream, width=100, highlight=False)
        self.quiet = quiet
        # the bar counts as the final lines do (BatchSummary.lines): runs whose mission did not
        # finish, this time or before, apart from usar's own errors
        self.unfinished = sum(r.outcome != "done" for r in (*plan.finished, *plan.invalid))
        self.errors = 0
        self.progress = Progress(
            TextColumn("[bold]runs[/]"),
            BarColumn(bar_width=30),
            MofNCompleteColumn(),
            TextColumn("did not finish {task.fields[unfinished]}, errors {task.fields[errors]}"),
            TimeElapsedColumn(),
            TextColumn("ETA"),
            TimeRemainingColumn(),
            console=self.console,
            disable=quiet,
            transient=False,
        )
        self.task = self.progress.add_task(
            "runs", total=len(plan.jobs), unfinished=self.unfinished, errors=0
        )
        if not quiet and (plan.finished or plan.invalid):
            self.console.print(
                f"{len(plan.finished)} runs finished before (not run again)"
                + (
                    f", {len(plan.invalid)} runs of submissions without a mission"
                    if plan.invalid
                    else ""
                )
            )

    def __enter__(self) -> _Progress:
        self.progress.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.progress.stop()

    def __call__(self, r: RunResult) -> None:
        if r.state == "error":
            self.errors += 1
        elif r.state == "graded" and r.outcome != "done":
            self.unfinished += 1
        self.progress.update(self.task, advance=1, unfinished=self.unfinished, errors=self.errors)
        if self.quiet or r.state == "interrupted":
            return
        if r.state == "error":
            first = safe_line(r.error.strip().splitlines()[0]) if r.error.strip() else ""
            self.console.print(f"ERROR {r.team} on {r.world}: {first}"[:100])
        else:
            self.console.print(
                f"{r.team} on {r.world}: {r.points:.4g}/{r.max_points:.4g}, "
                f"{r.outcome.replace('_', ' ')} ({r.wall_s:.0f} s)"[:100]
            )


def grade_class(
    plan: Plan,
    engine: Engine,
    *,
    gradescope: bool = False,
    visibility: str = "visible",
    quiet: bool = False,
    stream: TextIO | None = None,
    code: bool = False,
    code_template: str | None = None,
    code_jobs: int = 1,
) -> BatchSummary:
    """Execute the plan's runs, then write ``summary.csv``, ``summary.txt`` and (``gradescope``)
    each team's ``results.json``; with ``code``, each team's code submission graded beside its
    demo (:mod:`usar_replay.batch.code_grade`). KeyboardInterrupt propagates after the running
    runs are cut off (their logs closed, no manifest entry: the next batch redoes them)."""
    summary = BatchSummary(plan)
    with _Progress(plan, quiet, stream or sys.stderr) as progress:

        def on_result(r: RunResult) -> None:
            summary.results.append(r)
            progress(r)

        engine.run(plan.jobs, on_result)
    full = {w.name: max_points(w.scenario_toml) for w in plan.worlds}
    grades = collect(plan, full)
    out = plan.out_root
    if code:
        from dataclasses import replace

        from usar_replay.batch.code_grade import demo_builds, grade_code

        teams = [(s.team, s.path) for s in plan.submissions]
        builds = demo_builds(out, [t for t, _ in teams], [w.name for w in plan.worlds])
        grades = replace(grades, code=grade_code(teams, out, code_template, code_jobs, builds))
    write_text(out / SUMMARY_CSV, to_csv(grades), overwrite=True)
    summary.table = to_table(grades)
    write_text(out / SUMMARY_TXT, summary.table + "\n", overwrite=True)
    write_text(out / CLASS_FILE, class_json(grades), overwrite=True)
    write_text(out / CLASS_PAGE, class_page(grades, _no_link), overwrite=True)
    if gradescope:
        sources = {w.name: w.source for w in plan.worlds}
        for team in grades.teams:
            results = gradescope_results(
                grades,
                team,
                sources,
                execution_time_s=team_wall_s(plan, team, grades.worlds),
                visibility=visibility,
            )
            write_text(out / team / GRADESCOPE_FILE, gradescope_json(results), overwrite=True)
    return summary


def _no_link(_team: str, _world: str) -> None:
    """The batch's page links no run page: ``usar report OUT -o DIR`` writes them, and a class
    page that links each."""
    return None


def summary_paths(plan: Plan) -> tuple[Path, Path]:
    return plan.out_root / SUMMARY_CSV, plan.out_root / SUMMARY_TXT
