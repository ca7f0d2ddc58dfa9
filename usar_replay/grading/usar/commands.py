"""``<robot>.cmd_vel_one_publisher``: two publishers fighting over a robot (no points)."""

from __future__ import annotations

from usar_replay.grading.usar.observations import Observations
from usar_replay.grading.usar.rules import RULES
from usar_replay.grading.usar.words import plural, sim_s
from usar_replay.grading.verdict import Check

__all__ = ["one_cmd_vel_publisher"]


def one_cmd_vel_publisher(g: Observations, robot: str) -> Check:
    """``<robot>.cmd_vel_one_publisher``: never two different moving commands in one tick (no
    points of its own: the course's rubric loses them elsewhere on a robot that does not spin)."""
    count = g.cmd_conflicts[robot]
    first = g.cmd_conflict_ns[robot]
    return Check(
        id=f"{robot}.cmd_vel_one_publisher",
        rule=RULES["cmd_vel"].text,
        description=f"{robot}'s cmd_vel has one publisher at a time",
        passed=count == 0,
        points=0.0,
        max_points=0.0,
        measured="no conflicting commands"
        if count == 0
        else f"{plural(count, 'tick')} with two different commands, first at {sim_s(first or 0)}",
        threshold="one moving command per tick",
        evidence_ns=first,
        value=float(count),
        unit="ticks",
        limit=0.0,
        op="<=",
        evidence="" if first is None else "first tick with two commands",
    )
