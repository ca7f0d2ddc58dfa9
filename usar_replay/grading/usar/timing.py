"""Question 5, "10 minutes": ``time_limit``."""

from __future__ import annotations

from usar_replay.grading.usar.observations import Observations
from usar_replay.grading.usar.rules import RULES
from usar_replay.grading.verdict import Check

__all__ = ["time_limit"]


def time_limit(g: Observations, follower_home_ns: int | None) -> Check:
    """``time_limit``: the mission ended (the follower home, as :func:`follower_home` judges
    it) within the limit, counted from the log start."""
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
        measured=f"{took:.1f} s" if took is not None else "not completed (follower never home)",
        threshold=f"<= {limit:g} s",
        evidence_ns=follower_home_ns,
        value=took,
        unit="s",
        limit=limit,
        op="<=",
        evidence="" if follower_home_ns is None else "follower home",
    )
