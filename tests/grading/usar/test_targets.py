"""Question 1, targets reached: the one in-order check, and the explorer's targets."""

from __future__ import annotations

import pytest
from rubric_streams import (
    EXPLORER_HOME,
    TARGETS,
    S,
    drive,
    world,
)

from usar_replay.grading.usar import (
    Disc,
    Grader,
    explorer_targets,
    in_order,
)


def test_in_order_is_a_greedy_subsequence_of_arrivals() -> None:
    def disc(*entries: int) -> Disc:
        return Disc((0.0, 0.0), 1.0, 1.1, True, entries=list(entries))

    assert in_order([disc(5), disc(9), disc(12)]) == [5, 9, 12]
    # 2 reached only before 1: it fails, and 3 still counts after 1
    assert in_order([disc(5), disc(3), disc(12)]) == [5, None, 12]
    # passing 3 early does not matter when it is reached again in order
    assert in_order([disc(5), disc(9), disc(2, 14)]) == [5, 9, 14]
    # a skipped item does not block the later ones
    assert in_order([disc(), disc(9)]) == [None, 9]


def test_explorer_targets_in_order_with_units_and_evidence() -> None:
    g = Grader(world())
    t = drive(g, "explorer", [EXPLORER_HOME, TARGETS[1], TARGETS[0]], S)
    first, second = explorer_targets(g)
    assert first.passed and first.evidence_ns == 3 * S and first.evidence == "reached"
    assert first.value == pytest.approx(0.0) and first.unit == "m" and first.limit == 0.15
    assert not second.passed and second.points == 0 and second.max_points == 6
    assert "only before target_1" in second.measured and "out of order" in second.measured
    assert second.threshold == "<= 0.15 m, after target_1"
    assert t == 4 * S


def test_a_target_never_reached_says_how_close_and_when() -> None:
    g = Grader(world())
    drive(g, "explorer", [EXPLORER_HOME, (1.0, 0.0), (1.58, 0.0), (1.0, 0.0)], S)
    line = explorer_targets(g)[0]
    assert not line.passed
    assert line.measured == "never reached (closest 0.42 m at 3.0 s)"
    assert line.evidence_ns == 3 * S and line.evidence == "closest approach"
    assert line.value == pytest.approx(0.42)
