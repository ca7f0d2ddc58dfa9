"""Grading an opened log: wires :mod:`usar_replay.log.run` to the pure rubric.

Why this module is thin: a rubric (found by the run's assignment in
:mod:`usar_replay.grading.rubrics`) is pure and judged on messages; this module only opens the
recording once (:func:`usar_replay.log.run.open_run`), checks that it holds what the rubric
needs, feeds it the few topics it reads (camera frames are skipped without decoding, which is
what makes ``usar grade`` fast) and says whether the log was whole.
"""

from __future__ import annotations

import os
import time
from collections.abc import Collection
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from usar_replay.core.errors import MissingTopic
from usar_replay.core.safe_text import safe_line
from usar_replay.core.settings import Thresholds, load
from usar_replay.grading.rubrics import rubric_for
from usar_replay.grading.verdict import Check, FoundMarker, GradeReport, RubricGrader
from usar_replay.log.run import Run, open_run

if TYPE_CHECKING:
    from usar_replay.log.bag import BagWriter
    from usar_replay.world.scenario import Scenario

__all__ = [
    "Check",
    "GradeReport",
    "LiveGrade",
    "Thresholds",
    "grade_file",
    "grade_run",
    "load_thresholds",
    "never_ran",
    "observe_run",
    "with_goal_tolerances",
]

FAILED_OUTCOMES = {
    "crashed": "crashed",
    "hung": "hung",
    "out_of_memory": "ran out of memory",
    "refused": "was refused",
    "build_failed": "did not build",
}
"""The verdicts that end a run because of the mission's code, with the words a line shows."""


def load_thresholds(path: str | os.PathLike[str]) -> Thresholds:
    """Thresholds from a TOML file's ``[thresholds]`` table (the settings codec: names, units
    and ranges checked; other tables are ignored so one file can serve several tools)."""
    return load(Thresholds, Path(path), table="thresholds")


def with_goal_tolerances(
    thresholds: Thresholds | None, run: Run | None = None, settings: Any = None
) -> Thresholds:
    """``thresholds`` with each robot's move_base goal tolerance filled in where unset (rubric
    v3 widens a target's and a marker's radius by it): a ROS 1 log's, as the package's own
    move_base parameters gave it; else the run's ``mission.xy_tolerance`` (``settings``, or
    the log's recorded settings); else the course template's (the rubric's default)."""
    th = thresholds or Thresholds()
    ros1 = None
    if run is not None:
        from usar_replay.log import ros1_run

        ros1 = ros1_run.of(run)
        if settings is None and run.settings_recorded:
            settings = run.settings
    mission = getattr(settings, "mission", None)
    fallback = getattr(mission, "xy_tolerance", None) if ros1 is None else None
    found: dict[str, float | None] = {}
    for robot in ("explorer", "follower"):
        value = None if ros1 is None else ros1.xy_goal_tolerance(robot)
        found[robot] = value if value is not None else fallback
    return replace(
        th,
        explorer_goal_tolerance_m=th.explorer_goal_tolerance_m
        if th.explorer_goal_tolerance_m is not None
        else found["explorer"],
        follower_goal_tolerance_m=th.follower_goal_tolerance_m
        if th.follower_goal_tolerance_m is not None
        else found["follower"],
    )


def _learn_run(grader: RubricGrader, run: Run) -> None:
    """What the log says of the run that a rubric may judge by beside the messages: whether a
    ROS 1 package's node subscribed to ``/fiducial_transforms`` (a grader that has no
    ``detections_read`` does not ask)."""
    from usar_replay.log import ros1_run

    ran = ros1_run.of(run)
    if ran is not None and hasattr(grader, "detections_read"):
        grader.detections_read = ran.detections_read


def observe_run(run: Run, thresholds: Thresholds | None = None) -> RubricGrader:
    """The run's rubric grader, fed every message of the log it reads: the rubric's own
    observations (``usar record``'s summary counts markers with them). Nothing is required: a
    log without a topic gives a grader that saw none of it."""
    scenario = run.require_scenario()
    rubric = rubric_for(scenario)
    grader = rubric.grader(scenario, with_goal_tolerances(thresholds, run))
    _learn_run(grader, run)
    grader.start_ns = run.start_ns  # the run's clock starts with the log, whatever topic
    feed = grader.feed
    # the course's detections count as the world published them ("sim"), never a mission's
    trusted = {topic: ("sim",) for topic in rubric.trusted_topics}
    for topic, msg, t in run.reader.decoded(rubric.grade_topics, only_from=trusted):
        feed(topic, msg, t)
    return grader


def _check_required(
    path: str | os.PathLike[str], required: tuple[str, ...], topics: Collection[str]
) -> None:
    """:class:`MissingTopic` naming the required topics a complete log lacks."""
    missing = [t for t in required if t not in topics]
    if missing:
        raise MissingTopic(
            f"{path}: topic {missing[0]} is missing; it cannot be graded"
            + (f" (also missing: {', '.join(missing[1:])})" if missing[1:] else "")
        )


class LiveGrade:
    """The run's rubric grader fed while the recorder writes the log (:meth:`BagWriter.watch`):
    the same messages in the same order as :func:`grade_run` reads from the finished file, so
    :meth:`report` is the grade ``usar grade`` gives the file, without reading it again."""

    def __init__(
        self, scenario: Scenario, thresholds: Thresholds | None = None, settings: Any = None
    ) -> None:
        self.rubric = rubric_for(scenario)
        self.given = thresholds
        self.thresholds = with_goal_tolerances(thresholds, settings=settings)
        """Judged by: a ROS 1 package's own goal tolerances are known only once its log is
        written, so :meth:`report` grades the file again where they differ."""
        self.grader = self.rubric.grader(scenario, self.thresholds)
        self._writer: BagWriter | None = None
        self._last_ns = 0
        """The latest log time fed (ground truth comes every tick): did sim time pass?"""
        self.seconds = 0.0
        """Wall seconds spent grading so far: a resource count for the batch's grade limit
        (a grade bomb costs its time while it records), never part of a verdict."""

    def attach(self, writer: BagWriter, start_ns: int) -> None:
        """Watch ``writer`` from its first message on (written at ``start_ns``: the log's
        start, which the rubric's clock counts from)."""
        self.grader.start_ns = start_ns
        trusted = {topic: ("sim",) for topic in self.rubric.trusted_topics}
        writer.watch(self.rubric.grade_topics, self._feed, only_from=trusted)
        self._writer = writer

    def _feed(self, topic: str, msg: Any, t_ns: int) -> None:
        began = time.perf_counter()
        self._last_ns = max(self._last_ns, t_ns)
        try:
            self.grader.feed(topic, msg, t_ns)
        finally:
            self.seconds += time.perf_counter() - began

    def found_markers(self) -> tuple[FoundMarker, ...]:
        """The markers found so far, as the rubric counts them."""
        return self.grader.found_markers()

    def report(self, path: str | os.PathLike[str]) -> GradeReport:
        """The grade of the complete log at ``path`` (as :func:`grade_file` gives it;
        :class:`MissingTopic` when a topic the rubric requires was never written)."""
        written = self._writer.topics if self._writer is not None else frozenset()
        _check_required(path, self.rubric.required_topics, written)
        if self._writer is not None:
            run = open_run(path)
            if with_goal_tolerances(self.given, run) != self.thresholds:
                # the package's move_base said other tolerances than the live grader knew
                return grade_run(run, self.given)
            _learn_run(self.grader, run)
        report = self.grader.report(str(path), log_complete=True, log_problem="")
        if self._writer is None:
            return report
        w = self._writer
        return never_ran(report, w.outcome, w.outcome_reason, self._last_ns - report.start_ns)


def grade_run(run: Run, thresholds: Thresholds | None = None) -> GradeReport:
    """Grade an opened recording as recorded (no replay). A damaged log is graded as far as it
    goes and says so. A complete log without a topic the mission publishes (no detector node:
    no ``/fiducial_transforms``) is a graded run whose lines that need it fail and say why; one
    without a topic the simulator always writes (the rubric's ``required_topics``: ground
    truth) is not the log of a run and raises :class:`MissingTopic`."""
    began = time.perf_counter()  # only for JUnit's `time`: never part of the verdict
    rubric = rubric_for(run.require_scenario())
    if run.damage is None:
        _check_required(run.path, rubric.required_topics, run.topics)
    grader = observe_run(run, thresholds)
    problem = run.problem()
    report: GradeReport = grader.report(
        str(run.path), log_complete=not problem, log_problem=problem
    )
    if run.damage is None:
        report = never_ran(report, run.outcome, run.outcome_reason, run.end_ns - run.start_ns)
    return replace(report, seconds=time.perf_counter() - began, started_with=_started_with(run))


def _started_with(run: Run) -> str:
    """A ROS 1 log's start and its source, for the grade's reader (the TA checks it)."""
    from usar_replay.log import ros1_run

    ran = ros1_run.of(run)
    if ran is None:
        return ""
    return ran.started_with + (f" ({ran.start_source})" if ran.start_source else "")


def _gist(lines: list[str]) -> str:
    """The line of a verdict's reason that says what happened: a traceback's last (the
    exception), else the first, with the line it introduces (``...before it connected:``)."""
    if lines[0].startswith("Traceback"):
        return lines[-1]
    if lines[0].endswith(":") and len(lines) > 1:
        return f"{lines[0]} {lines[1]}"
    return lines[0]


def never_ran(report: GradeReport, outcome: str, reason: str, span_ns: int) -> GradeReport:
    """``report`` with every line failed, saying why, when the mission's code ended the run
    before its first tick was done (``outcome`` a failure and no sim time passed: a crash at
    import, a graph that never got ready, a package that did not build). Why: such a log holds
    only the world at t0 (issue 31: every log is gradable), and what the world shows by itself
    then (the course's detector seeing a marker from the start) is not the team's work."""
    words = FAILED_OUTCOMES.get(outcome)
    if words is None or span_ns > 0:
        return report
    lines = [line.strip() for line in reason.splitlines() if line.strip()]
    said = f"the mission {words} before its first tick"
    if lines:
        said += ": " + safe_line(_gist(lines))[:200]
    checks = tuple(
        replace(c, passed=False, points=0.0, measured=said, evidence_ns=None, evidence="")
        for c in report.checks
    )
    return replace(report, checks=checks)


def grade_file(path: str | os.PathLike[str], thresholds: Thresholds | None = None) -> GradeReport:
    """Open a recording and grade it (:func:`grade_run`)."""
    return grade_run(open_run(path), thresholds)
