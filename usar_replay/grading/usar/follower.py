"""Question 4, the follower: ``explorer.home_before_follower``, ``follower.marker_k`` (a stop
within the handout's stand-off plus the package's goal tolerance, in ID order) and
``follower.home`` (on its own, never through the visits)."""

from __future__ import annotations

import math

from usar_replay.grading.usar.observations import Observations
from usar_replay.grading.usar.rules import RULES
from usar_replay.grading.usar.targets import visit_checks
from usar_replay.grading.usar.words import point, sim_s
from usar_replay.grading.verdict import Check

__all__ = ["explorer_home_before_follower", "follower_home", "follower_markers"]


def explorer_home_before_follower(g: Observations, last_target_ns: int, last_target: str) -> Check:
    """``explorer.home_before_follower``: home after its last target, before the follower moved."""
    th = g.th
    moved = g.follower_moved_ns
    home = g.explorer_home_disc.first_after(last_target_ns)
    ok = home is not None and (moved is None or moved >= home)
    follower = "the follower never moved" if moved is None else f"follower moved at {sim_s(moved)}"
    after = f" after {last_target}" if last_target else ""
    if home is None:
        measured = f"never home{after} (ended {g.explorer_home_disc.last_m:.2f} m away); {follower}"
    else:
        measured = f"home at {sim_s(home)}; {follower}"
    if ok:
        evidence_ns, evidence = home, "explorer home"
    elif moved is not None:
        evidence_ns, evidence = moved, "follower moved"
    else:
        evidence_ns, evidence = None, ""
    return Check(
        id="explorer.home_before_follower",
        rule=RULES["explorer_home"].text,
        description="explorer returned home before the follower moved",
        passed=ok,
        points=4.0 if ok else 0.0,
        max_points=4.0,
        measured=measured,
        threshold=f"home within {th.home_m:g} m after the last target, before the follower "
        f"moves {th.follower_moved_m:g} m",
        evidence_ns=evidence_ns,
        value=None if home is None else home / 1e9,
        unit="s",
        limit=None if moved is None else moved / 1e9,
        op="<=",
        evidence=evidence,
    )


def follower_markers(g: Observations) -> list[Check]:
    """``follower.marker_k``: the follower visited each marker, in ID order."""
    ids = list(g.marker_discs)
    return visit_checks(
        ids=[f"follower.marker_{k}" for k in ids],
        descriptions=[f"follower stopped at marker {k} in ID order" for k in ids],
        names=[f"marker {k}" for k in ids],
        discs=list(g.marker_discs.values()),
        radius=g.visit_radius,
        points_total=12.0,
        verb="stopped",
        order="ID order",
        rule=RULES["visits"].text,
    )


def follower_home(g: Observations) -> Check:
    """``follower.home``: the follower left home and came back, after the explorer was home
    (where the explorer never came home: after the follower moved). Judged on its own, never
    through the visits: a follower whose visits failed may still come home."""
    d = g.follower_home_disc
    explorer_home = g.explorer_home_disc.entries[0] if g.explorer_home_disc.entries else None
    after = explorer_home if explorer_home is not None else -1
    fh = d.first_after(after)
    since = "" if explorer_home is None else f" after the explorer ({sim_s(explorer_home)})"
    if fh is None:
        left = g.follower_moved_ns is not None
        measured = (
            f"never home{since} (ended {d.last_m:.2f} m away)" if left else "never left home"
        )
        value = d.last_m if math.isfinite(d.last_m) and left else None
    else:
        value = d.stay_at(fh)
        measured = f"home at {sim_s(fh)} (closest {value:.3f} m){since}"
    return Check(
        id="follower.home",
        rule=RULES["follower_home"].text,
        description="follower left and returned home, after the explorer",
        passed=fh is not None,
        points=4.0 if fh is not None else 0.0,
        max_points=4.0,
        measured=measured,
        threshold=f"within {g.th.home_m:g} m of {point(g.follower_home)}, after leaving it",
        evidence_ns=fh,
        value=value,
        unit="m",
        limit=g.th.home_m,
        op="<=",
        evidence="" if fh is None else "follower home",
    )
