"""Question 1, "targets reached": ``explorer.target_k``, and the one place order is judged.

Order is judged once, by :func:`in_order`, as a *subsequence* of arrivals: item k passes when it
was reached after the in-order arrival at the previous reached item (greedily, earliest first).
An explorer that skips target_2 fails only ``explorer.target_2``; one that drives past target_3
on its way to target_1 is not punished; one that visits 2, 1, 3, 4 fails ``explorer.target_2``.
The follower's markers (:mod:`.follower`) are judged by the same :func:`visit_checks`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from usar_replay.grading.usar.observations import Disc, Observations
from usar_replay.grading.usar.rules import RULES
from usar_replay.grading.usar.words import point, sim_s
from usar_replay.grading.verdict import Check

__all__ = ["explorer_targets", "in_order", "last_reached", "visit_checks"]


def in_order(discs: Sequence[Disc]) -> list[int | None]:
    """The arrival time at each disc, taken in order as a subsequence of the robot's arrivals.

    Greedy: each item's arrival is its first entry after the previous *reached* item's arrival;
    None for an item not reached in order (never, or only before). The one place order is
    judged, for the explorer's targets and the follower's markers alike.
    """
    out: list[int | None] = []
    prev = -1
    for d in discs:
        t = d.first_after(prev)
        out.append(t)
        if t is not None:
            prev = t
    return out


def last_reached(names: Sequence[str], arrivals: Sequence[int | None]) -> tuple[int, str]:
    """(time, name) of the last item reached in order; (-1, "") when none was."""
    last = (-1, "")
    for name, t in zip(names, arrivals, strict=True):
        if t is not None:
            last = (t, name)
    return last


def visit_checks(
    *,
    ids: Sequence[str],
    descriptions: Sequence[str],
    names: Sequence[str],
    discs: Sequence[Disc],
    radius: float,
    points_total: float,
    verb: str,
    order: str,
    rule: str,
) -> list[Check]:
    """The lines "robot reached item k, in order": one wording for targets and markers."""
    arrivals = in_order(discs)
    each = points_total / max(len(discs), 1)
    checks: list[Check] = []
    prev_name = ""
    for i, d in enumerate(discs):
        t = arrivals[i]
        after = f", after {prev_name}" if prev_name else ""
        value: float | None
        evidence_ns: int | None
        if t is not None:
            stay = d.stay_at(t)
            measured = f"{verb} at {sim_s(t)} (closest {stay:.3f} m)"
            value, evidence_ns, evidence = stay, t, verb
        else:
            where = d.closest_evidence()
            closest = f"closest {d.closest_m:.2f} m" + (
                f" at {sim_s(where)}" if where is not None else ", where it started"
            )
            if d.entries:
                measured = f"{verb} only before {prev_name} (out of {order}; {closest})"
            else:
                measured = f"never {verb} ({closest})"
            value = d.closest_m if math.isfinite(d.closest_m) else None
            evidence_ns, evidence = where, ("closest approach" if where is not None else "")
        checks.append(
            Check(
                id=ids[i],
                description=descriptions[i],
                passed=t is not None,
                points=each if t is not None else 0.0,
                max_points=each,
                measured=measured,
                threshold=f"<= {radius:g} m{after}",
                evidence_ns=evidence_ns,
                value=value,
                unit="m",
                limit=radius,
                op="<=",
                evidence=evidence,
                rule=rule,
            )
        )
        if t is not None:
            prev_name = names[i]
    return checks


def explorer_targets(g: Observations) -> list[Check]:
    """``explorer.target_k``: the explorer's true position reached each target, in order."""
    n = len(g.targets)
    return visit_checks(
        ids=[f"explorer.target_{k + 1}" for k in range(n)],
        descriptions=[
            f"explorer reached target_{k + 1} {point(t)}" + (" in order" if k else "")
            for k, t in enumerate(g.targets)
        ],
        names=[f"target_{k + 1}" for k in range(n)],
        discs=g.target_discs,
        radius=g.target_radius,
        points_total=12.0,
        verb="reached",
        order="order",
        rule=RULES["targets"].text,
    )
