"""Question 5, 10 minutes."""

from __future__ import annotations

from rubric_streams import (
    S,
    good_run,
    judge_failed,
    world,
)

from usar_replay.core import contract
from usar_replay.core.settings import Thresholds
from usar_replay.grading.usar import (
    Grader,
    judge,
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


def test_nothing_after_the_time_limit_scores() -> None:
    """A TA stops watching at the limit (issue 51): cut between the two markers' detections,
    every line whose evidence came before the cut passes as in the whole run, every one after
    it fails, and ``time_limit`` says the follower was not home within the limit."""
    whole = Grader(world())
    good_run(whole)
    assert not judge_failed(whole)
    evidence = {c.id: c.evidence_ns for c in judge(whole) if c.evidence_ns is not None}
    cut_ns = evidence["marker_1.detected"] - S // 2
    cut = Grader(world(time_limit_s=(cut_ns - S) / S))  # the log starts at S
    good_run(cut)
    failed = set(judge_failed(cut))
    before = {k for k, t in evidence.items() if t <= cut_ns}
    after = {k for k, t in evidence.items() if t > cut_ns}
    assert before and after and "follower.home" in after
    assert not failed & before, failed & before
    assert after <= failed, after - failed
    line = time_limit(cut, None)
    assert line.measured == f"not completed (follower not home within {(cut_ns - S) / S:g} s)"
