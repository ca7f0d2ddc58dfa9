"""Grading an opened log: wires :mod:`usar_replay.run` to the pure rubric.

Why this module is thin: the rubric (:mod:`usar_replay.rubric`) is pure and judged on messages;
this module only opens the recording once (:func:`usar_replay.run.open_run`), checks that it
holds what the rubric needs, feeds it the few topics it reads (camera frames are skipped without
decoding, which is what makes ``usar grade`` fast) and says whether the log was whole.
"""

from __future__ import annotations

import importlib
import os
import time
from dataclasses import replace
from pathlib import Path
from types import ModuleType

from usar_replay.errors import MissingTopic
from usar_replay.rubric import (
    DETECTION_MEMORY_NS,
    GRADE_TOPICS,
    MAX_VISITS,
    REQUIRED_TOPICS,
    Check,
    Grader,
    GradeReport,
)
from usar_replay.run import Run, open_run
from usar_replay.scenario import Scenario
from usar_replay.settings import Thresholds, load

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
    "rubric_for",
]


def load_thresholds(path: str | os.PathLike[str]) -> Thresholds:
    """Thresholds from a TOML file's ``[thresholds]`` table (the settings codec: names, units
    and ranges checked; other tables are ignored so one file can serve several tools)."""
    return load(Thresholds, Path(path), table="thresholds")


def rubric_for(scenario: Scenario) -> ModuleType:
    """The module holding the rubric of the scenario's assignment: it has ``Grader(scenario,
    thresholds)`` (``feed``, ``report``), ``GRADE_TOPICS`` and ``REQUIRED_TOPICS``. US&R's is
    :mod:`usar_replay.rubric`. Named by the assignment, imported here (a rubric module imports
    the shared ``Check``/``GradeReport`` shapes, so the assignment cannot import it)."""
    from usar_replay.assignment import of

    return importlib.import_module(of(scenario).rubric_module)


def grade_run(run: Run, thresholds: Thresholds | None = None) -> GradeReport:
    """Grade an opened recording as recorded (no replay). A damaged log is graded as far as it
    goes and says so; a complete log that lacks a topic the rubric needs raises
    :class:`MissingTopic`."""
    began = time.perf_counter()  # only for JUnit's `time`: never part of the verdict
    scenario = run.require_scenario()
    rubric = rubric_for(scenario)
    grader = rubric.Grader(scenario, thresholds)
    grader.start_ns = run.start_ns  # the run's clock starts with the log, whatever topic
    if run.damage is None:
        missing = [t for t in rubric.REQUIRED_TOPICS if t not in run.topics]
        if missing:
            raise MissingTopic(
                f"{run.path}: topic {missing[0]} is missing; it cannot be graded"
                + (f" (also missing: {', '.join(missing[1:])})" if missing[1:] else "")
            )
    feed = grader.feed
    for topic, msg, t in run.reader.decoded(rubric.GRADE_TOPICS):
        feed(topic, msg, t)
    problem = run.problem()
    report: GradeReport = grader.report(
        str(run.path), log_complete=not problem, log_problem=problem
    )
    return replace(report, seconds=time.perf_counter() - began)


def grade_file(path: str | os.PathLike[str], thresholds: Thresholds | None = None) -> GradeReport:
    """Open a recording and grade it (:func:`grade_run`)."""
    return grade_run(open_run(path), thresholds)
