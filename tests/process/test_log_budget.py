"""process/log_budget: a run's message bytes counted tick by tick against its budget."""

from __future__ import annotations

from usar_replay.process.log_budget import DEFAULT_MAX_LOG_MIB, LogBudget

MIB = 1024 * 1024


def _wire(n: int) -> tuple[str, str, bytes]:
    return ("/topic", "std_msgs/msg/String", b"x" * n)


def test_ticks_within_the_budget_pass_and_are_counted() -> None:
    budget = LogBudget(1)
    budget.inputs([_wire(100), _wire(50)])
    assert budget.outputs([_wire(10)]) == ""
    assert budget.used == 160
    assert DEFAULT_MAX_LOG_MIB == 2048


def test_the_tick_that_crosses_the_budget_says_why() -> None:
    budget = LogBudget(1)
    budget.inputs([_wire(MIB - 10)])
    assert budget.outputs([_wire(10)]) == ""  # exactly the budget is within it
    budget.inputs([])
    why = budget.outputs([_wire(1)])
    assert why == (
        "the log passed its budget of 1 MiB (--max-log-mib) with this tick's 1 bytes of the "
        f"mission's messages ({MIB + 1} bytes of messages in all)"
    )


def test_inputs_are_paired_with_outputs_in_tick_order() -> None:
    budget = LogBudget(1)
    budget.inputs([_wire(MIB)])  # tick 1: the whole budget in inputs
    budget.inputs([_wire(5)])  # tick 2 sent before tick 1's outputs came back
    assert budget.outputs([]) == ""  # tick 1: just fits
    assert "with this tick's 5 bytes" in budget.outputs([_wire(5)])  # tick 2: over
    assert budget.used == MIB + 10


def test_a_budget_of_zero_is_none() -> None:
    budget = LogBudget(0)
    budget.inputs([_wire(3 * MIB)])
    assert budget.outputs([_wire(3 * MIB)]) == ""
    assert budget.used == 6 * MIB
