"""What grading one team's code may cost: tool calls, PDFs tried, wall time.

Why: every tool call is bounded (:mod:`usar_replay.code.tools`: 30 s, rlimits), but a team
decides how many calls it causes. Six PDFs of 1,500 pages sharing one content stream took
pdftotext 30 s each, 181 s for one team, and at the walk's 1 GiB a team could hold the whole
class for hours (issue 50). So each team grades under a :class:`Budget`: past any of its
counts, every further tool call of that team returns at once with "the team's budget" as the
limit it went past (a team's finding, as a tool's own limit is), and one verdict line says
what was spent (:attr:`Spend.spent`). A batch's code grading then waits for a team at most its
wall time (plus one tool's shortest wind-down), whatever the team holds.

The figures: the course's packages use 4-6 tool calls (doxygen, cppcheck, one clang-format per
indent width, pdfinfo and pdftotext twice for a report, hunspell) and 2-5 s of wall time;
``--compile`` adds one g++ call (~4 s of CPU) per translation unit, at most a few dozen in a
real package. The budget is ten times that, so an honest team never meets it.

The wall clock here is a budget, never a grade's input: what was measured before the budget
was spent is the same on every machine; only a team that meets the budget can be graded
differently on a slower one, and its verdict line says so.
"""

from __future__ import annotations

import contextlib
import contextvars
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass

__all__ = ["DEFAULT", "Budget", "Spend", "current", "spending"]


@dataclass(frozen=True, slots=True)
class Budget:
    tool_calls: int = 96
    """Tool runs a team may cause (doxygen, cppcheck, clang-format, g++, poppler, hunspell)."""
    pdfs: int = 5
    """PDFs whose first page and page count are read to choose the report."""
    wall_s: float = 120.0
    """Seconds of wall time from the team's first tool call."""

    def words(self) -> str:
        return f"{self.tool_calls} tool calls, {self.pdfs} PDFs, {self.wall_s:g} s"


DEFAULT = Budget()


class Spend:
    """One team's use of its :class:`Budget` (shared by the threads grading that team)."""

    def __init__(self, budget: Budget = DEFAULT) -> None:
        self.budget = budget
        self._lock = threading.Lock()
        self._calls = 0
        self._pdfs = 0
        self._start: float | None = None
        self._blocked = ""
        self._said: list[str] = []

    @property
    def spent(self) -> str:
        """'' or what the team went past, in words (its verdict line)."""
        return "; ".join(self._said)

    def _over(self, why: str) -> str:
        """Calls are spent: every later one is refused with the first reason."""
        if not self._blocked:
            self._blocked = why
            self._said.append(why)
        return self._blocked

    def call(self) -> tuple[float, str]:
        """Take one tool call: (seconds it may run, '') or (0, what was spent)."""
        with self._lock:
            now = time.monotonic()
            if self._start is None:
                self._start = now
            if self._blocked:
                return 0.0, self._blocked
            left = self.budget.wall_s - (now - self._start)
            if left <= 0:
                return 0.0, self._over(f"its {self.budget.wall_s:g} s of wall time")
            if self._calls >= self.budget.tool_calls:
                return 0.0, self._over(f"its {self.budget.tool_calls} tool calls")
            self._calls += 1
            return left, ""

    def timed_out(self) -> str:
        """A call cut short by the wall budget: the budget is spent (what is said)."""
        with self._lock:
            return self._over(f"its {self.budget.wall_s:g} s of wall time")

    def pdf(self) -> bool:
        """Take one PDF to try; False when the team's PDFs are spent (said once; the tool
        calls go on: the chosen report is still read)."""
        with self._lock:
            if self._pdfs >= self.budget.pdfs:
                said = f"its {self.budget.pdfs} PDFs tried"
                if said not in self._said:
                    self._said.append(said)
                return False
            self._pdfs += 1
            return True

    @property
    def calls(self) -> int:
        return self._calls


_CURRENT: contextvars.ContextVar[Spend | None] = contextvars.ContextVar("usar_code_spend",
                                                                       default=None)  # fmt: skip


def current() -> Spend | None:
    """The team's :class:`Spend` this thread grades under (None: unbounded, a direct call)."""
    return _CURRENT.get()


@contextlib.contextmanager
def spending(budget: Budget = DEFAULT) -> Iterator[Spend]:
    """Grade one team under ``budget`` in this thread (and in threads started with a copy of
    its context: :func:`contextvars.copy_context`)."""
    spend = Spend(budget)
    token = _CURRENT.set(spend)
    try:
        yield spend
    finally:
        _CURRENT.reset(token)
