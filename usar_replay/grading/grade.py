"""Grading an opened log: wires :mod:`usar_replay.log.run` to the pure rubric.

Why this module is thin: the rubric (:mod:`usar_replay.grading.rubric_usar`) is pure and judged on
messages; this module only opens the recording once (:func:`usar_replay.log.run.open_run`), checks
that it holds what the rubric needs, feeds it the few topics it reads (camera frames are skipped
without decoding, which is what makes ``usar grade`` fast) and says whether the log was whole.
"""

from __future__ import annotations

import os
import time
from dataclasses import replace
from pathlib import Path

from usar_replay.core.errors import MissingTopic
from usar_replay.core.settings import Thresholds, load
from usar_replay.grading.rubric_usar import (
    DETECTION_MEMORY_NS,
    GRADE_TOPICS,
    MAX_VISITS,
    REQUIRED_TOPICS,
    Grader,
)
from usar_replay.grading.verdict import Check, GradeReport, Rubric, RubricGrader
from usar_replay.log.run import Run, open_run
from usar_replay.world.scenario import Scenario

__all__ = [
    "DETECTION_MEMORY_NS",
    "GRADE_TOPICS",
    "MAX_VISITS",
    "REQUIRED_TOPICS",
    "Check",
    "GradeReport",
    "Grader",
    "Thresholds",
    "grade_file",
    "grade_run",
    "load_thresholds",
    "observe_run",
    "rubric_for",
]


def load_thresholds(path: str | os.PathLike[str]) -> Thresholds:
    """Thresholds from a TOML file's ``[thresholds]`` table (the settings codec: names, units
    and ranges checked; other tables are ignored so one file can serve several tools)."""
    return load(Thresholds, Path(path), table="thresholds")


def rubric_for(scenario: Scenario) -> Rubric:
    """The rubric of the scenario's assignment (:attr:`Assignment.rubric`)."""
    from usar_replay.grading.assignment import of

    return of(scenario).rubric()


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


def grade_run(run: Run, thresholds: Thresholds | None = None) -> GradeReport:
    """Grade an opened recording as recorded (no replay). A damaged log is graded as far as it
    goes and says so. A complete log without a topic the mission publishes (no detector node:
    no ``/fiducial_transforms``) is a graded run whose lines that need it fail and say why; one
    without a topic the simulator always writes (the rubric's ``required_topics``: ground
    truth) is not the log of a run and raises :class:`MissingTopic`."""
    began = time.perf_counter()  # only for JUnit's `time`: never part of the verdict
    rubric = rubric_for(run.require_scenario())
    if run.damage is None:
        missing = [t for t in rubric.required_topics if t not in run.topics]
        if missing:
            raise MissingTopic(
                f"{run.path}: topic {missing[0]} is missing; it cannot be graded"
                + (f" (also missing: {', '.join(missing[1:])})" if missing[1:] else "")
            )
    grader = observe_run(run, thresholds)
    problem = run.problem()
    report: GradeReport = grader.report(
        str(run.path), log_complete=not problem, log_problem=problem
    )
    return replace(report, seconds=time.perf_counter() - began)


def grade_file(path: str | os.PathLike[str], thresholds: Thresholds | None = None) -> GradeReport:
    """Open a recording and grade it (:func:`grade_run`)."""
    return grade_run(open_run(path), thresholds)
