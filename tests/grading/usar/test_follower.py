"""Question 4, the follower: a visit is a stop within the stand-off plus the goal
tolerance, in ID order; home on its own."""

from __future__ import annotations

import pytest
from rubric_streams import (
    EXPLORER_HOME,
    FOLLOWER_HOME,
    TARGETS,
    S,
    drive,
    world,
)

from usar_replay.core.settings import Thresholds
from usar_replay.grading.usar import (
    Grader,
    explorer_home_before_follower,
    follower_home,
    follower_markers,
    time_limit,
)


def test_a_robot_that_never_moved_has_no_evidence_time() -> None:
    """Nothing happened: the closest approach is where it started, not something to look at."""
    g = Grader(world())
    drive(g, "follower", [FOLLOWER_HOME, FOLLOWER_HOME], S)
    for line in follower_markers(g):
        assert not line.passed and line.evidence_ns is None and line.evidence == ""
        assert (
            line.measured.startswith("never stopped (closest")
            and "where it started" in line.measured
        )
        assert "never" in line.measured and "at never" not in line.measured


def test_explorer_home_before_the_follower_moved() -> None:
    g = Grader(world())
    drive(g, "follower", [FOLLOWER_HOME], S)
    t = drive(g, "explorer", [EXPLORER_HOME, TARGETS[0], TARGETS[1]], S)
    drive(g, "follower", [(0.5, -1.0)], t)  # moves at 4 s, explorer still out
    drive(g, "explorer", [EXPLORER_HOME], t + S)  # home at 5 s
    line = explorer_home_before_follower(g, 3 * S, "target_2")
    assert not line.passed
    assert line.measured == "home at 5.0 s; follower moved at 4.0 s"
    assert line.evidence_ns == 4 * S and line.evidence == "follower moved"
    assert line.value == 5.0 and line.limit == 4.0 and line.unit == "s"


def test_explorer_never_home_has_no_home_time() -> None:
    g = Grader(world())
    drive(g, "explorer", [EXPLORER_HOME, TARGETS[0]], S)
    line = explorer_home_before_follower(g, 2 * S, "target_1")
    assert not line.passed and line.value is None and line.evidence_ns is None
    assert (
        line.measured == "never home after target_1 (ended 2.00 m away); the follower never moved"
    )


def test_follower_markers_in_id_order_then_home() -> None:
    g = Grader(world())
    path = [FOLLOWER_HOME, (4.0, 0.7), (4.0, 0.7), (2.0, 0.7), (2.0, 0.7), FOLLOWER_HOME]
    drive(g, "follower", path, S)
    m0, m1 = follower_markers(g)
    assert m0.passed and m0.evidence_ns == 5 * S and m0.value == pytest.approx(0.3)
    assert not m1.passed and "out of ID order" in m1.measured
    home = follower_home(g)  # on its own: whatever the visits
    assert home.passed and home.evidence_ns == 6 * S and home.value == pytest.approx(0.0)


def test_follower_home_and_time_stand_on_their_own() -> None:
    """A follower that visited no marker (it stopped 1 m short of each) still came home, after
    the explorer: follower.home and time_limit pass; one that never left home fails both."""
    g = Grader(world())
    t = drive(g, "follower", [FOLLOWER_HOME], S)
    t = drive(g, "explorer", [EXPLORER_HOME, (1.0, 0.0), EXPLORER_HOME], t)
    drive(g, "follower", [(1.0, -1.0), (2.0, -0.3), (2.0, -0.3), FOLLOWER_HOME], t)
    assert not any(c.passed for c in follower_markers(g))
    home = follower_home(g)
    assert home.passed and home.evidence_ns == 8 * S, home.measured
    assert "after the explorer (4.0 s)" in home.measured
    assert time_limit(g, home.evidence_ns).passed
    still = Grader(world())
    drive(still, "follower", [FOLLOWER_HOME, FOLLOWER_HOME], S)
    assert follower_home(still).measured == "never left home"
    assert not time_limit(still, follower_home(still).evidence_ns).passed


def test_a_visit_is_a_stop_within_the_stand_off_and_the_goal_tolerance() -> None:
    """The handout's 0.4 m stand-off (in x and in y) plus the template's 0.05 m tolerance plus
    the overshoot: a stop 0.45 m in front of marker 0 and one 0.6 m off on the diagonal of
    marker 1 pass; driving past at 0.1 m without stopping is no visit; a package's own 0.4 m
    tolerance widens the radius."""
    g = Grader(world())
    assert g.visit_radius == pytest.approx(0.4 * 2**0.5 + 0.05 + 0.10)
    front, diagonal = (2.0, 1.0 - 0.45), (4.0 - 0.6 / 2**0.5, 1.0 - 0.6 / 2**0.5)
    path = [FOLLOWER_HOME, front, front, diagonal, diagonal, FOLLOWER_HOME]
    drive(g, "follower", path, S)
    m0, m1 = follower_markers(g)
    assert m0.passed and m0.value == pytest.approx(0.45), m0.measured
    assert m1.passed and m1.value == pytest.approx(0.6), m1.measured
    assert m0.threshold.startswith("<= 0.715685 m")
    past = Grader(world())
    drive(past, "follower", [FOLLOWER_HOME, (2.0, 0.9), (4.0, 0.9), FOLLOWER_HOME], S)
    p0, p1 = follower_markers(past)
    assert not p0.passed and not p1.passed and "never stopped" in p0.measured, p0.measured
    far = (2.0, 1.0 - 0.95)  # 0.95 m out: beyond 0.77 m with the template's tolerance
    short = Grader(world())
    drive(short, "follower", [FOLLOWER_HOME, far, far], S)
    assert not follower_markers(short)[0].passed
    wide = Grader(world(), Thresholds(follower_goal_tolerance_m=0.4))  # the package's own
    drive(wide, "follower", [FOLLOWER_HOME, far, far], S)
    assert follower_markers(wide)[0].passed
