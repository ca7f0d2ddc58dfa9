"""A run's byte budget for its log: what the simulator and the mission put in it, capped.

Why: every byte a mission publishes is written to the log, and the per-message and per-tick caps
(:mod:`usar_replay.node.boundary_check`) still let a mission write 8 MiB of noise per message
and many messages per tick: 1.17 GB per sim-second, a full disk on the grader's machine. The
budget counts the bytes of each tick's messages (the simulator's inputs and the mission's
outputs, as CDR: what the log stores, before compression) in tick order, so a recording and its
replay reach the same verdict at the same tick. Crossing it ends the run as ``refused``; the
tick's outputs are not written and the log is closed as usual, gradeable.

The default (:data:`DEFAULT_MAX_LOG_MIB`, 2 GiB) is about forty times the course world's run
(measured: 49 MiB of messages, a 15 MB file, for the built-in mission's 466 s of sim time):
no honest run comes near it.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence

from usar_replay.core.limits import RunLimits

__all__ = ["DEFAULT_MAX_LOG_MIB", "LogBudget"]

DEFAULT_MAX_LOG_MIB = RunLimits().max_log_mib
"""The default budget in MiB (``--max-log-mib``; 0: none)."""

Wire = tuple[str, str, bytes]


class LogBudget:
    """Counts a run's message bytes, tick by tick; :meth:`outputs` says when they are over."""

    def __init__(self, max_mib: int) -> None:
        self.max_mib = max_mib
        self.max_bytes = max_mib * 1024 * 1024
        self.used = 0
        self._sent: deque[int] = deque()

    def inputs(self, items: Sequence[Wire]) -> None:
        """A tick handed to the mission (counted when its outputs come back, in order)."""
        self._sent.append(sum(len(data) for _, _, data in items))

    def outputs(self, items: Sequence[Wire]) -> str:
        """The oldest sent tick's outputs: '' when the tick fits, else why it does not."""
        tick_in = self._sent.popleft() if self._sent else 0
        tick_out = sum(len(data) for _, _, data in items)
        self.used += tick_in + tick_out
        if self.max_bytes <= 0 or self.used <= self.max_bytes:
            return ""
        return (
            f"the log passed its budget of {self.max_mib} MiB (--max-log-mib) with this tick's "
            f"{tick_out} bytes of the mission's messages ({self.used} bytes of messages in all)"
        )
