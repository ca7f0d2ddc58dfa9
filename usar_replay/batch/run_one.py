"""One batch run in its own process: record a team's mission on a world, grade it, write the
run's files. ``python -m usar_replay.batch.run_one`` reads the
:class:`~usar_replay.batch.plan.RunJob` as JSON on stdin.

Why a process of its own (started by :mod:`usar_replay.batch.engines`): the recorder holds a
pybullet world and an open log; a crash in it, a run past its wall-clock limit or a Ctrl-C ends this
process only, and the engine can kill it and its mission process as one process group. The
working directory is the run's own scratch folder; the mission process (started by
:func:`usar_replay.pipeline.record.record`) inherits it and the job's limits
(:class:`~usar_replay.core.limits.RunLimits`).

Signals: SIGTERM means "past the wall-clock limit": the log is closed (marked interrupted), graded
as far as it goes, and the run is finished with the outcome ``wall_limit``; a SIGTERM while the
log is graded stops the grading, and the grade (every line failed) says ``wall_limit``. SIGINT
(Ctrl-C) means "cut off": the log is closed and the process exits 130 without a manifest entry,
so the next batch redoes the run. Exit 0: the run's files are written.

Grading is bounded too: past ``grade_s`` wall seconds (``--grade-limit``) it stops and the
grade says ``grade_limit`` with every line failed (a log built to be slow to grade, a grade
bomb, is that team's verdict; the other teams are graded as usual).
"""

from __future__ import annotations

import hashlib
import json
import os
import signal
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any

from usar_replay.batch.plan import (
    GRADE_FORMAT,
    ROS1_TARGET_PREFIX,
    RUN_FORMAT,
    RunJob,
    finished_record,
)
from usar_replay.core.errors import UsageError, UsarError
from usar_replay.core.outfiles import write_text
from usar_replay.core.safe_text import json_data

if TYPE_CHECKING:
    from usar_replay.core.settings import Thresholds
    from usar_replay.grading.grade import LiveGrade
    from usar_replay.process.mission_process import MissionLimits

__all__ = ["grade_job", "main", "max_points", "record_run", "rubric"]


class WallLimit(KeyboardInterrupt):
    """SIGTERM from the engine: the run is past its wall-clock limit. A KeyboardInterrupt so
    that the recorder closes the log the way it does for Ctrl-C."""


def _on_sigterm(_signum: int, _frame: object) -> None:
    raise WallLimit


class GradeStopped(BaseException):
    """Grading was stopped (its time limit, or the run's wall-clock limit): ``outcome`` is
    ``grade_limit`` or ``wall_limit``. A BaseException so that no ``except Exception`` in the
    grader takes it for a problem of the log."""

    def __init__(self, outcome: str, reason: str) -> None:
        super().__init__(reason)
        self.outcome = outcome
        self.reason = reason


@contextmanager
def grading_deadline(seconds: float) -> Iterator[None]:
    """Within the block, SIGALRM after ``seconds`` of wall time and SIGTERM (the engine's wall
    limit) raise :class:`GradeStopped`; after it SIGTERM is ignored (writing the files is
    quick)."""

    def on_alarm(_signum: int, _frame: object) -> None:
        raise GradeStopped("grade_limit", f"grading took more than {seconds:g} s of wall time")

    def on_term(_signum: int, _frame: object) -> None:
        raise GradeStopped("wall_limit", "grading was stopped at the run's wall-clock limit")

    previous = signal.signal(signal.SIGALRM, on_alarm)
    signal.signal(signal.SIGTERM, on_term)
    signal.setitimer(signal.ITIMER_REAL, max(seconds, 1e-3))
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
        signal.signal(signal.SIGALRM, previous)


def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _thresholds(thresholds_toml: str) -> Thresholds | None:
    """The batch's thresholds, parsed from the job's data (None: the course's)."""
    from usar_replay.core.settings import Thresholds, from_toml

    if not thresholds_toml:
        return None
    return from_toml(Thresholds, thresholds_toml, "thresholds.toml", table="thresholds")


def rubric(
    log: Path,
    scenario_toml: str,
    thresholds_toml: str,
    graded: LiveGrade | None = None,
    stopped: str = "",
) -> dict[str, Any]:
    """The grade of one log as plain data: the only place that knows grade.py's names (so a
    rename there is a fix here). ``graded``: the recorder's
    :class:`~usar_replay.grading.grade.LiveGrade` of this log, fed with these thresholds while
    it was written (then the file is not read again); else the file is graded. A log that
    cannot be graded at all (the mission crashed before the first tick, no log), or whose
    grading was ``stopped`` (why), gets every line of its assignment's rubric failed with 0
    points."""
    from usar_replay.grading.grade import grade_file
    from usar_replay.grading.rubrics import rubric_for
    from usar_replay.world.scenario_toml import from_toml

    thresholds = _thresholds(thresholds_toml)
    try:
        if stopped:
            raise UsarError(stopped)
        report = graded.report(log) if graded is not None else grade_file(log, thresholds)
        zero = False
    except UsarError as err:
        scenario = from_toml(scenario_toml)
        report = (
            rubric_for(scenario)
            .grader(scenario, thresholds)
            .report(str(log), log_complete=False, log_problem=str(err))
        )
        zero = True
    checks: list[dict[str, Any]] = [
        {
            "id": c.id,
            "description": c.description,
            "passed": bool(c.passed) and not zero,
            "points": 0.0 if zero else round(c.points, 3),
            "max_points": round(c.max_points, 3),
            "measured": c.measured,
        }
        for c in report.checks
    ]
    return {
        "points": round(sum(float(c["points"]) for c in checks), 3),
        "max_points": round(sum(float(c["max_points"]) for c in checks), 3),
        "log_complete": report.log_complete,
        "log_problem": report.log_problem,
        "checks": checks,
    }


def grade_job(
    job: RunJob, record: dict[str, Any], graded: LiveGrade | None = None
) -> dict[str, Any]:
    """Grade the run's log (``graded``: as :func:`rubric` takes it) and write
    ``<world>.grade.json`` (atomically)."""
    log = job.path(".mcap")
    outcome, reason = record["outcome"], record["outcome_reason"]
    import usar_replay.grading.grade  # noqa: F401 - imported before the clock starts

    limit_s = job.run_limits.grade_s
    try:
        if graded is not None and graded.seconds > limit_s:  # graded while it recorded
            raise GradeStopped(
                "grade_limit", f"grading took more than {limit_s:g} s of wall time"
            )
        with grading_deadline(limit_s):
            lines = rubric(log, job.scenario_toml, job.thresholds_toml, graded)
    except GradeStopped as stop:
        outcome, reason = stop.outcome, f"{stop.reason} (the run: {outcome})"
        lines = rubric(log, job.scenario_toml, job.thresholds_toml, stopped=stop.reason)
    grade = {
        "format": GRADE_FORMAT,
        "team": job.team,
        "world": job.world,
        "outcome": outcome,
        "outcome_reason": reason,
        "log": log.name,
        "log_sha256": record["log_sha256"],
        "thresholds_sha256": job.thresholds_sha256,
        **_start(job, log),
        **lines,
    }
    text = json.dumps(json_data(grade), indent=2, sort_keys=True) + "\n"  # team text escaped
    write_text(job.path(".grade.json"), text, overwrite=True)
    return grade


def _start(job: RunJob, log: Path) -> dict[str, str]:
    """A ROS 1 team's start and where it was read: as the log's ``ros1.toml`` says it ran,
    else as the plan read it (a run that ended before its package started)."""
    if not job.target.startswith(ROS1_TARGET_PREFIX):
        return {}
    start, source = job.start, job.start_source
    try:
        from usar_replay.log import ros1_run
        from usar_replay.log.run import open_run

        ran = ros1_run.of(open_run(log, check="summary"))
        if ran is not None:
            start, source = ran.started_with, ran.start_source or source
    except (UsarError, OSError):
        pass
    return {"start": start, "start_source": source}


def _mission_limits(job: RunJob) -> MissionLimits:
    """The job's limits (:attr:`RunJob.run_limits`) and where its mission runs: the team's
    submission read-only, nothing of OUT_DIR (this run's grade and log are written by this
    process, outside it), never run bare by accident."""
    from usar_replay.process.mission_process import MissionLimits
    from usar_replay.sandbox.audit_guard import GuardPolicy

    guard = None
    own = str(Path(job.submission_path).resolve())
    if job.sandbox:
        work = str(job.work_dir.resolve())
        guard = GuardPolicy(
            read_roots=(own,),
            write_roots=(work,),
            deny_roots=(job.out_root, job.submissions_root),
            own_roots=(own, work),
        )
    return MissionLimits.of(
        job.run_limits,
        guard=guard,
        kernel_sandbox="required" if job.sandbox else "off",
        read_roots=(own,),
        hidden=(job.out_root,),  # never mounted, unless it lies in the team's folder
    )


def _record_ros1(job: RunJob, scenario: Any, log: Path, settings: Any, watchdog: Any) -> Any:
    """A catkin package: built and run by the ROS 1 bridge, in its own network namespace (its
    master and ports are its own, so teams run in parallel). The audit guard does not apply
    to native code; the time and memory limits do."""
    import dataclasses

    from usar_replay.ros1.process import Ros1Options
    from usar_replay.ros1.record import record_ros1
    from usar_replay.ros1.starts_file import InstructorStart

    limits = dataclasses.replace(_mission_limits(job), guard=None)
    package = job.target.removeprefix(ROS1_TARGET_PREFIX)
    options = Ros1Options()
    told = InstructorStart.from_json(job.instructor_start) if job.instructor_start else None
    return record_ros1(
        scenario, log, package, settings, watchdog, limits=limits, options=options, instructor=told
    )


def record_run(job: RunJob) -> tuple[dict[str, Any], LiveGrade | None]:
    """Record the run (replacing whatever a cut-off run left): its manifest entry, and the
    grade the recorder fed while writing the log (None when the file must be graded: a run
    past its wall-clock limit, or a ROS 1 package's run).

    Raises KeyboardInterrupt (not WallLimit) when cut off: then nothing is written."""
    from usar_replay.core.settings import RunSettings
    from usar_replay.core.settings import from_toml as settings_from_toml
    from usar_replay.pipeline.record import record
    from usar_replay.world.scenario_toml import from_toml

    log = job.path(".mcap")
    for stale in (job.path(".run.json"), job.path(".grade.json"), log):
        stale.unlink(missing_ok=True)
    scenario = from_toml(job.scenario_toml, source=f"world {job.world}")
    settings = settings_from_toml(RunSettings, job.settings_toml, source="batch settings")
    parent = os.getppid()

    def watchdog(_progress: object) -> None:
        # an engine that died (a killed Ray worker) leaves this process to its init: stop
        if os.getppid() != parent:
            raise KeyboardInterrupt

    start = time.perf_counter()  # wall time is for people and the wall-limit verdict only
    graded = None
    build = ""  # a ROS 1 package's build: "cached", "catkin_make 12.3 s" (not the log's)
    pacing = ""  # a ROS 1 run's holds and capped ticks (the capped ones are not the log's)
    compiler: dict[str, Any] | None = None  # what its build's compiler said, for --code
    try:
        if job.target.startswith(ROS1_TARGET_PREFIX):
            try:
                result = _record_ros1(job, scenario, log, settings, watchdog)
            except UsageError as err:  # the team's package cannot be started: its verdict
                result = None
                outcome, reason, sim_s = "no_mission", str(err), 0.0
        else:
            result = record(
                scenario,
                log,
                settings,
                watchdog,
                mission=job.target,
                limits=_mission_limits(job),
                thresholds=_thresholds(job.thresholds_toml),
            )
            graded = result.grade
        if result is not None:
            outcome, reason = result.outcome, result.outcome_reason
            sim_s = result.sim_duration_s
            build, pacing = result.build, result.pacing
            if job.target.startswith(ROS1_TARGET_PREFIX):
                from usar_replay.batch.code_grade import compiler_record

                compiler = compiler_record(build, result.build_log, reason)
    except WallLimit:
        wall = job.run_limits.wall_s
        outcome, reason = "wall_limit", f"the run took more than {wall:g} s of wall time"
        sim_s = 0.0
    wall_s = time.perf_counter() - start
    rec = {
        "format": RUN_FORMAT,
        "team": job.team,
        "world": job.world,
        "inputs": job.inputs,
        "inputs_key": job.inputs_key,
        "log": log.name,
        "log_bytes": log.stat().st_size if log.exists() else 0,
        "log_sha256": _sha256(log) if log.exists() else "",
        "outcome": outcome,
        "outcome_reason": reason,
        "sim_duration_s": round(sim_s, 3),
        "build": build,
        "pacing": pacing,
        "wall_s": round(wall_s, 3),
    }
    if compiler is not None:
        rec["compiler"] = compiler
    return rec, graded


def _write_record(job: RunJob, rec: dict[str, Any]) -> None:
    text = json.dumps(json_data(rec), indent=2, sort_keys=True) + "\n"  # team text escaped
    write_text(job.path(".run.json"), text, overwrite=True)


def run(job: RunJob) -> dict[str, Any]:
    """Record (unless only the grade is missing), grade, then write the manifest entry last."""
    signal.signal(signal.SIGTERM, _on_sigterm)
    record = finished_record(job) if job.grade_only else None
    if record is None:
        record, graded = record_run(job)
        signal.signal(signal.SIGTERM, signal.SIG_IGN)  # until grading, which honours it again
        job.path(".run.json").unlink(missing_ok=True)
        grade = grade_job(job, record, graded)
        _write_record(job, record)
    else:
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
        grade = grade_job(job, record)
    return {
        "outcome": grade["outcome"],
        "points": grade["points"],
        "max_points": grade["max_points"],
        "wall_s": record["wall_s"],
    }


def main() -> int:
    from usar_replay.batch.run_state import main_prelude

    main_prelude()  # the same state whichever engine started this process
    job = RunJob.from_json(sys.stdin.read())
    try:
        run(job)
    except KeyboardInterrupt:
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(main())


def max_points(scenario_toml: str) -> float:
    """The full marks of the world's assignment's rubric (for runs that have no grade)."""
    from usar_replay.grading.rubrics import rubric_for
    from usar_replay.world.scenario_toml import from_toml

    scenario = from_toml(scenario_toml)
    report = rubric_for(scenario).grader(scenario, None).report("", log_complete=False)
    return round(sum(c.max_points for c in report.checks), 3)
