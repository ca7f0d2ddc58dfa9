"""A rubric line's verdict and a recording's grade: the shapes every rubric returns.

Why a module of its own: the US&R and the ROS 2 rubrics, the reports (table, JSON, JUnit, CSV,
HTML) and the viewer all speak these two types; neither rubric should have to import the other
to share them.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

from usar_replay.core import msgs
from usar_replay.core.settings import Thresholds
from usar_replay.world.scenario import Scenario

__all__ = ["Check", "FoundMarker", "GradeReport", "Rubric", "RubricGrader"]


@dataclass(frozen=True, slots=True)
class Check:
    """One rubric line's verdict.

    ``measured`` and ``threshold`` are the words for a person; ``value``/``limit`` (in ``unit``,
    compared with ``op``) are the same facts as numbers for a machine. ``evidence_ns`` is the sim
    time to look at and ``evidence`` what happened then; both are empty when nothing did.
    """

    id: str
    description: str
    passed: bool
    points: float
    max_points: float
    measured: str
    threshold: str
    evidence_ns: int | None
    detail: str = ""
    value: float | None = None
    unit: str = ""
    limit: float | None = None
    op: str = ""
    evidence: str = ""
    rule: str = ""
    """Which rule the line applied and its source (the TA's rule, as a TA can check it;
    '' where a rubric does not say)."""


@dataclass(frozen=True, slots=True)
class GradeReport:
    """All rubric lines of one recording, plus whether the log itself was complete."""

    source: str
    checks: tuple[Check, ...]
    start_ns: int
    log_complete: bool = True
    log_problem: str = ""
    thresholds: Thresholds | None = None
    """The thresholds judged by, ``time_limit_s`` resolved from the scenario."""
    scenario: str = ""
    """The scenario's name."""
    seconds: float = 0.0
    """Wall time spent grading (JUnit's ``time``); never part of the verdict."""
    rubric: str = ""
    """The rubric's name (its assignment's: ``usar``, ``ros2-final``)."""
    rubric_version: int = 0
    """Which version of that rubric judged (:attr:`Rubric.version`; 0: not said)."""
    started_with: str = ""
    """A ROS 1 package's start as it ran and where it was read (``roslaunch P F; rosrun P N
    (doc/instructions.txt lines 3, 4)``); '' for a Python mission."""

    @property
    def points(self) -> float:
        return sum(c.points for c in self.checks)

    @property
    def max_points(self) -> float:
        return sum(c.max_points for c in self.checks)

    @property
    def passed(self) -> bool:
        return all(c.passed for c in self.checks)

    def check(self, check_id: str) -> Check:
        """The line with this id (KeyError when the scenario has no such line)."""
        for c in self.checks:
            if c.id == check_id:
                return c
        raise KeyError(check_id)

    def failed_ids(self) -> list[str]:
        """Ids of the lines that failed, in rubric order."""
        return [c.id for c in self.checks if not c.passed]


@dataclass(frozen=True, slots=True)
class FoundMarker:
    """A marker the run found, as its rubric counts it: what ``usar record``'s summary shows,
    so that it agrees with ``usar grade`` for any mission (not only one that publishes the
    built-in mission's ``/explorer/marker_poses``)."""

    marker_id: int
    text: str
    """The rubric's words for the evidence (``3 broadcasts, worst error 0.8 cm``)."""
    error_m: float | None = None
    """The worst distance of what the run said about the marker's place from the truth, where
    the rubric measures one."""


class RubricGrader(Protocol):
    """A streaming grader: fed one message at a time, then asked for the report."""

    start_ns: int | None

    def feed(self, topic: str, msg: msgs.Message | None, t_ns: int) -> None: ...

    def found_markers(self) -> tuple[FoundMarker, ...]:
        """The markers found so far, as this rubric counts them, by ID."""
        ...

    def report(
        self, source: str, *, log_complete: bool = True, log_problem: str = ""
    ) -> GradeReport: ...


@dataclass(frozen=True, slots=True)
class Rubric:
    """One assignment's rubric: how to make its grader and which topics it reads.

    Why a value and not a module: an :class:`~usar_replay.world.assignment.Assignment`
    carries a factory for it, so grade, replay and the CLI ask the run's assignment for its
    rubric and never look a module up by name."""

    grader: Callable[[Scenario, Thresholds | None], RubricGrader]
    grade_topics: tuple[str, ...]
    """The topics the rubric reads; everything else in a log is skipped without decoding."""
    required_topics: tuple[str, ...]
    """Without these a log cannot be graded at all."""
    trusted_topics: tuple[str, ...] = ()
    version: int = 1
    """Raised whenever a line's meaning changes, so that the same log may grade differently:
    every report says which version judged it (``docs/reports.md``)."""
    """Topics that count only as the world published them (the ``sim`` publisher: the course's
    detector on the recorder's side), never as a mission did: a forged copy is not graded."""
