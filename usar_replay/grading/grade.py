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
    "observe_run",
]


def load_thresholds(path: str | os.PathLike[str]) -> Thresholds:
    """Thresholds from a TOML file's ``[thresholds]`` table (the settings codec: names, units
    and ranges checked; other tables are ignored so one file can serve several tools)."""
    return load(Thresholds, Path(path), table="thresholds")


def observe_run(run: Run, thresholds: Thresholds | None = None) -> RubricGrader:
    """The run's rubric grader, fed every message of the log it reads: the rubric's own
    observations (``usar record``'s summary counts markers with them). Nothing is required: a
    log without a topic gives a grader that saw none of it."""
    scenario = run.require_scenario()
    rubric = rubric_for(scenario)
    grader = rubric.grader(scenario, thresholds)
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

    def __init__(self, scenario: Scenario, thresholds: Thresholds | None = None) -> None:
        self.rubric = rubric_for(scenario)
        self.grader = self.rubric.grader(scenario, thresholds)
        self._writer: BagWriter | None = None
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

    def _feed(self, *args: Any) -> None:
        began = time.perf_counter()
        try:
            self.grader.feed(*args)
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
        return self.grader.report(str(path), log_complete=True, log_problem="")


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
    return replace(report, seconds=time.perf_counter() - began)


def grade_file(path: str | os.PathLike[str], thresholds: Thresholds | None = None) -> GradeReport:
    """Open a recording and grade it (:func:`grade_run`)."""
    return grade_run(open_run(path), thresholds)
