"""Two publishers on one robot's cmd_vel (no points)."""

from __future__ import annotations

from rubric_streams import (
    good_run,
    world,
)

from usar_replay.core import msgs
from usar_replay.grading.usar import (
    Grader,
    judge,
)


def test_two_moving_commands_in_one_tick_are_two_publishers() -> None:
    """A spin timer and a navigator both driving the explorer: caught; a stop after a command
    (a goal ending) is not a fight (at 500 s: within the world's time limit, which the test
    sets above it, since nothing after the limit is observed)."""
    g = Grader(world(time_limit_s=600.0))
    good_run(g)
    t = 500_000_000_000
    spin = msgs.Twist(angular=msgs.Vector3(z=0.1))
    drive = msgs.Twist(linear=msgs.Vector3(x=0.2))
    g.feed("/follower/cmd_vel", drive, t)
    g.feed("/follower/cmd_vel", msgs.Twist(), t)  # the navigator stops: fine
    g.feed("/explorer/cmd_vel", drive, t + 1)
    g.feed("/explorer/cmd_vel", spin, t + 1)  # two publishers in one tick
    checks = {c.id: c for c in judge(g)}
    assert checks["follower.cmd_vel_one_publisher"].passed
    bad = checks["explorer.cmd_vel_one_publisher"]
    assert not bad.passed and bad.value == 1.0 and bad.evidence_ns == t + 1
    assert bad.max_points == 0.0  # it flags the run without moving the course's 60 points
