"""code/budget: a team's tool calls, PDFs and wall time are counted, and past them every
further call of that team is refused at once, said once."""

from __future__ import annotations

import contextvars
from pathlib import Path

from usar_replay.code import budget
from usar_replay.code.budget import Budget, Spend, spending
from usar_replay.code.tools import run_tool


def test_calls_are_counted_and_refused_past_the_budget() -> None:
    spend = Spend(Budget(tool_calls=2, pdfs=1, wall_s=60))
    assert spend.call()[1] == "" and spend.call()[1] == ""
    assert spend.call() == (0.0, "its 2 tool calls")
    assert spend.call() == (0.0, "its 2 tool calls")  # every later one, same words
    assert spend.pdf() is True and spend.pdf() is False and spend.pdf() is False
    assert spend.spent == "its 2 tool calls; its 1 PDFs tried"
    assert spend.calls == 2


def test_wall_time_spent_refuses_the_next_call() -> None:
    spend = Spend(Budget(wall_s=0.0))
    assert spend.call() == (0.0, "its 0 s of wall time")
    assert spend.spent == "its 0 s of wall time"


def test_pdfs_spent_leave_the_calls_open() -> None:
    """The report chosen among the PDFs tried is still read: only calls and time block."""
    spend = Spend(Budget(pdfs=0))
    assert spend.pdf() is False
    left, why = spend.call()
    assert why == "" and left > 0


def test_run_tool_takes_from_the_team_in_this_thread_and_its_copies(tmp_path: Path) -> None:
    assert budget.current() is None
    with spending(Budget(tool_calls=1)) as spend:
        assert budget.current() is spend
        assert run_tool(["true"], tmp_path, sandbox=False).limit == ""
        ctx = contextvars.copy_context()  # what compile's pool runs each unit in
        ran = ctx.run(run_tool, ["true"], tmp_path, sandbox=False)
        assert ran.limit == "the team's budget (its 1 tool calls)"
    assert budget.current() is None
    assert run_tool(["true"], tmp_path, sandbox=False).limit == ""  # no team: unbounded


def test_a_call_is_cut_at_the_teams_wall_time(tmp_path: Path) -> None:
    with spending(Budget(wall_s=1.0)) as spend:
        ran = run_tool(["sleep", "30"], tmp_path, sandbox=False)
    assert ran.limit == "the team's budget (its 1 s of wall time)"
    assert spend.spent == "its 1 s of wall time"
