"""Question 5, "10 minutes": ``time_limit``, and the cut that makes the limit the TA's clock.

Why the cut lives here: a TA stops watching at 10 minutes (the world's ``time_limit_s``, or the
thresholds' own), so what a robot does after that is not seen and scores nothing, on any line.
The recorder lets a run go on a few seconds past the limit
(:data:`usar_replay.pipeline.record.TIME_LIMIT_GRACE_S`); :func:`seen_by_the_ta` is the one test
the grader applies to every message before it observes it."""

from __future__ import annotations

from usar_replay.grading.usar.observations import Observations
from usar_replay.grading.usar.rules import RULES
from usar_replay.grading.verdict import Check

__all__ = ["limit_ns", "seen_by_the_ta", "time_limit"]


def limit_ns(g: Observations) -> int:
    """The time limit in ns of log time (the thresholds' ``time_limit_s``, else the world's);
    read per message, so kept to two attribute reads (no :meth:`resolved_thresholds` copy)."""
    limit = g.th.time_limit_s
    return int((limit if limit is not None else g.scenario.time_limit_s) * 1e9)


def seen_by_the_ta(g: Observations, t_ns: int) -> bool:
    """Whether a message at log time ``t_ns`` is within the time limit, counted from the log
    start (before the start is known, every message is: the first one sets it)."""
    return g.start_ns is None or t_ns - g.start_ns <= limit_ns(g)


def time_limit(g: Observations, follower_home_ns: int | None) -> Check:
    """``time_limit``: the mission ended (the follower home, as :func:`follower_home` judges
    it) within the limit, counted from the log start (a home after it is not seen at all:
    :func:`seen_by_the_ta`)."""
    limit = g.resolved_thresholds().time_limit_s or 0.0
    t0 = g.start_ns or 0
    took = None if follower_home_ns is None else (follower_home_ns - t0) / 1e9
    ok = took is not None and took <= limit
    return Check(
        id="time_limit",
        rule=RULES["time_limit"].text,
        description="whole task completed within the time limit",
        passed=ok,
        points=4.0 if ok else 0.0,
        max_points=4.0,
        measured=f"{took:.1f} s"
        if took is not None
        else f"not completed (follower not home within {limit:g} s)",
        threshold=f"<= {limit:g} s",
        evidence_ns=follower_home_ns,
        value=took,
        unit="s",
        limit=limit,
        op="<=",
        evidence="" if follower_home_ns is None else "follower home",
    )
