"""What a change of code or settings costs: the rubric lines whose verdict or points differ
between two grades of one world (the recording's and a replay's).

Why a module of its own: ``usar replay --mission fix.py LOG`` lists changed poses and goals,
but a student's question is "which rubric lines, how many points"; answering it needs only two
:class:`GradeReport` values, so this stays pure (no log, no process) and the CLI prints it.
"""

from __future__ import annotations

import textwrap
from dataclasses import dataclass

from usar_replay.grading.verdict import Check, GradeReport

__all__ = ["DeltaRow", "RubricDelta", "rubric_delta"]


@dataclass(frozen=True, slots=True)
class DeltaRow:
    """One rubric line whose outcome changed; ``before``/``after`` are None for a line that only
    one of the two grades has."""

    id: str
    before: Check | None
    after: Check | None

    @property
    def points_before(self) -> float:
        return 0.0 if self.before is None else self.before.points

    @property
    def points_after(self) -> float:
        return 0.0 if self.after is None else self.after.points

    @property
    def points(self) -> float:
        """Points gained (positive) or lost (negative)."""
        return self.points_after - self.points_before


@dataclass(frozen=True, slots=True)
class RubricDelta:
    """The changed lines, in rubric order, and both totals."""

    rows: tuple[DeltaRow, ...]
    total_before: float
    total_after: float
    max_points: float

    def lines(self, width: int = 100) -> list[str]:
        """What ``usar replay`` prints: a header, per changed rubric line its id, verdict before
        and after and the points, then what was measured before -> after; the total before ->
        after. Each line fits ``width`` columns."""
        total = (
            f"  total {_pts(self.total_before)} -> {_pts(self.total_after)}"
            f" of {_pts(self.max_points)} ({_signed(self.total_after - self.total_before)})"
        )
        if not self.rows:
            return ["Rubric: no line changes.", total]
        out = ["Rubric lines that change (recorded -> replayed):"]
        idw = min(max(len(r.id) for r in self.rows), 40)
        vw = max(len(_verdict(r.before)) for r in self.rows)
        for r in self.rows:
            out.append(
                f"  {_clip(r.id, idw):<{idw}}  {_verdict(r.before):<{vw}} -> "
                f"{_verdict(r.after):<{vw}}  {_signed(r.points)}"
            )
            out += textwrap.wrap(
                f"{_measured(r.before)} -> {_measured(r.after)}",
                width,
                initial_indent=" " * 6,
                subsequent_indent=" " * 8,
                break_on_hyphens=False,
            )
        out.append(total)
        return out

    def as_dict(self) -> dict[str, object]:
        """Plain data for ``usar replay --json`` (``rubric_delta``)."""
        return {
            "total_before": self.total_before,
            "total_after": self.total_after,
            "max_points": self.max_points,
            "lines": [
                {
                    "id": r.id,
                    "passed_before": None if r.before is None else r.before.passed,
                    "passed_after": None if r.after is None else r.after.passed,
                    "points_before": r.points_before,
                    "points_after": r.points_after,
                    "points": r.points,
                    "measured_before": "" if r.before is None else r.before.measured,
                    "measured_after": "" if r.after is None else r.after.measured,
                }
                for r in self.rows
            ],
        }


def rubric_delta(before: GradeReport, after: GradeReport) -> RubricDelta:
    """The lines whose pass/fail or points differ, in ``before``'s order then lines only
    ``after`` has. A line whose measurement moved but whose verdict and points did not is not a
    change a student pays for, so it is left out."""
    after_by_id = {c.id: c for c in after.checks}
    before_ids = {c.id for c in before.checks}
    rows: list[DeltaRow] = []
    for b in before.checks:
        a = after_by_id.get(b.id)
        if a is None or a.passed != b.passed or a.points != b.points:
            rows.append(DeltaRow(b.id, b, a))
    rows += [DeltaRow(a.id, None, a) for a in after.checks if a.id not in before_ids]
    return RubricDelta(
        rows=tuple(rows),
        total_before=before.points,
        total_after=after.points,
        max_points=max(before.max_points, after.max_points),
    )


def _pts(x: float) -> str:
    return f"{x:g}"


def _signed(x: float) -> str:
    return f"{x:+g} pts" if x else "0 pts"


def _verdict(c: Check | None) -> str:
    if c is None:
        return "(none)"
    return f"{'PASS' if c.passed else 'FAIL'} {_pts(c.points)}/{_pts(c.max_points)}"


def _measured(c: Check | None) -> str:
    return "-" if c is None or not c.measured else c.measured


def _clip(text: str, width: int) -> str:
    return text if len(text) <= width else text[: max(width - 3, 0)] + "..."
