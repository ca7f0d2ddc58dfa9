"""Question 5, 10 minutes."""

from __future__ import annotations

from rubric_streams import (
    S,
    world,
)

from usar_replay.core import contract
from usar_replay.core.settings import Thresholds
from usar_replay.grading.usar import (
    Grader,
    time_limit,
)


def test_time_limit_counts_from_the_log_start() -> None:
    g = Grader(world(time_limit_s=3.0))
    g.feed(contract.ROSOUT, None, S)
    assert time_limit(g, 3 * S).passed
    late = time_limit(g, 5 * S)
    assert not late.passed and late.measured == "4.0 s" and late.threshold == "<= 3 s"
    assert late.value == 4.0 and late.limit == 3.0
    never = time_limit(g, None)
    assert not never.passed and never.value is None and never.evidence_ns is None
    th = Grader(world(), Thresholds(time_limit_s=50.0))
    assert th.resolved_thresholds().time_limit_s == 50.0
    assert Grader(world()).resolved_thresholds().time_limit_s == 100.0
