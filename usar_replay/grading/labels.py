"""Where the report's numbered evidence circles go: near their point, never on each other, never
past the map's edge.

Why a module of its own: on the map of a run many rubric lines have their evidence at one
place (the start, a target where the explorer spun), and circles drawn at the points themselves
covered each other ("19,20" over "1,2" at the start) or were cut by the frame. Placement is plain
geometry on circles, kept pure (no matplotlib) so a test can check it: a circle that cannot sit
on its point moves out along a ring of candidate spots, and the page draws a leader line back.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

__all__ = ["Label", "diameter_pt", "place"]

DIRECTIONS = 12
"""Candidate directions on each ring, starting up and going clockwise (deterministic)."""
RINGS = 12
"""How many rings of growing distance are tried before a label is left on its point."""


@dataclass(frozen=True, slots=True)
class Label:
    """A circle with ``text``: it stands for ``anchor`` and is drawn at ``center``."""

    text: str
    anchor: tuple[float, float]
    center: tuple[float, float]
    radius: float

    @property
    def moved(self) -> bool:
        return self.center != self.anchor


def diameter_pt(text: str, fontsize: float) -> float:
    """A circle's diameter in points that holds ``text`` (digits and commas) at ``fontsize``:
    a digit is about 0.64 em wide in the default sans font, plus a margin of 0.9 em."""
    return max(1.0, 0.64 * len(text) + 0.9) * fontsize


def place(
    labels: Sequence[tuple[str, tuple[float, float], float]],
    bounds: tuple[float, float, float, float],
    gap: float = 0.0,
) -> list[Label]:
    """Place circles ``(text, anchor, radius)`` in order: each at its anchor if it fits there,
    else at the first candidate on rings around it (distance growing by one diameter) that is at
    least the two radii plus ``gap`` from every circle placed before and inside ``bounds``
    (``xmin, xmax, ymin, ymax``). All in one unit (the map's metres)."""
    placed: list[Label] = []
    for text, anchor, r in labels:
        center = _first_free(anchor, r, placed, bounds, gap)
        placed.append(Label(text, anchor, center, r))
    return placed


def _first_free(
    anchor: tuple[float, float],
    r: float,
    placed: Sequence[Label],
    bounds: tuple[float, float, float, float],
    gap: float,
) -> tuple[float, float]:
    xmin, xmax, ymin, ymax = bounds
    inside = (xmin + r, max(xmin + r, xmax - r), ymin + r, max(ymin + r, ymax - r))
    start = (min(max(anchor[0], inside[0]), inside[1]), min(max(anchor[1], inside[2]), inside[3]))
    if _free(start, r, placed, gap):
        return start
    for ring in range(1, RINGS + 1):
        dist = ring * (2 * r + gap)
        for k in range(DIRECTIONS):
            a = math.pi / 2 - 2 * math.pi * k / DIRECTIONS
            c = (start[0] + dist * math.cos(a), start[1] + dist * math.sin(a))
            within = inside[0] <= c[0] <= inside[1] and inside[2] <= c[1] <= inside[3]
            if within and _free(c, r, placed, gap):
                return c
    return start  # a map too crowded for its size: on its point, as before


def _free(c: tuple[float, float], r: float, placed: Sequence[Label], gap: float) -> bool:
    return all(math.dist(c, p.center) >= r + p.radius + gap - 1e-12 for p in placed)
