"""How the rubric's lines say times, counts and places (one wording for every line)."""

from __future__ import annotations

__all__ = ["plural", "point", "sim_s"]


def sim_s(t_ns: int) -> str:
    """A sim time as the log, ``usar info`` and the ``usar view`` timeline show it."""
    return f"{t_ns / 1e9:.1f} s"


def plural(count: int, word: str) -> str:
    """``1 frame``, ``2 frames``."""
    return f"{count} {word}" + ("" if count == 1 else "s")


def point(p: tuple[float, float]) -> str:
    return f"({p[0]:.2f}, {p[1]:.2f})"
