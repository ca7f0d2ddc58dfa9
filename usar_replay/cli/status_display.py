"""`usar record`'s live status: one self-rewriting block on stderr while a mission runs.

Why a block and not one line: a ROS 1 launch file starts several nodes that log, and one line
can show only one of them (a follower's "waiting" hid the explorer's search for 200 s). On a
terminal the status line is followed by one line per node (its last ``/rosout`` line), redrawn
in place by rich's :class:`~rich.live.Live`; a mission with one node keeps the single line.
Where stderr is not a terminal (CI, a pipe), a plain status line every 30 sim seconds, which
names the most recent new line of any node (:class:`usar_replay.pipeline.status_line.NodeLines`).
Every text is a mission's: it goes through :func:`usar_replay.core.safe_text.safe_line`.
"""

from __future__ import annotations

import shutil
import sys
from typing import TYPE_CHECKING, TextIO

from usar_replay.core.safe_text import safe_line

if TYPE_CHECKING:
    from rich.live import Live
    from rich.text import Text

    from usar_replay.pipeline.record import Progress

__all__ = ["MAX_NODE_LINES", "StatusDisplay", "status_lines"]

MAX_NODE_LINES = 6
"""Nodes shown one per line; more are summed up in one last line."""


def status_lines(p: Progress, width: int, per_node: bool) -> list[str]:
    """The block for ``p``, each line cut to ``width`` columns: the status line, then (with
    ``per_node`` and more than one node logging) one ``  [node] line`` per node."""
    head = (
        f"sim {p.sim_time_s:7.1f} s | markers {p.markers_found}/{p.markers_total} | "
        f"frames {p.frames}"
    )
    if not per_node or len(p.node_lines) < 2:
        return [f"{head} | {safe_line(p.last_log)}"[:width]]
    lines = [head[:width]]
    shown = p.node_lines[:MAX_NODE_LINES]
    for node, text in shown:
        lines.append(f"  [{safe_line(node)}] {safe_line(text)}"[:width])
    if len(p.node_lines) > len(shown):
        lines.append(f"  ... and {len(p.node_lines) - len(shown)} more nodes"[:width])
    return lines


class StatusDisplay:
    """The live block on a terminal, a plain line every 30 sim-s elsewhere (module doc)."""

    def __init__(self, stream: TextIO | None = None, tty: bool | None = None) -> None:
        self.stream = stream if stream is not None else sys.stderr
        self.tty = self.stream.isatty() if tty is None else tty
        self.width = min(shutil.get_terminal_size((100, 24)).columns, 100) - 1
        self.last_print = -1e9
        self._live: Live | None = None

    def __call__(self, p: Progress) -> None:
        every = 0.5 if self.tty else 30.0
        if p.sim_time_s - self.last_print < every:
            return
        self.last_print = p.sim_time_s
        if not self.tty:
            print(status_lines(p, self.width, per_node=False)[0], file=self.stream, flush=True)
            return
        from rich.text import Text

        block = Text("\n".join(status_lines(p, self.width, per_node=True)), no_wrap=True)
        if self._live is None:
            self._live = self._start(block)
        self._live.update(block, refresh=True)

    def _start(self, first: Text) -> Live:
        from rich.console import Console
        from rich.live import Live

        console = Console(file=self.stream, force_terminal=True, width=self.width + 1)
        live = Live(
            first,
            console=console,
            auto_refresh=False,
            transient=False,
            redirect_stdout=False,
            redirect_stderr=False,
        )
        live.start()
        return live

    def close(self) -> None:
        """Leave the last block on screen, the cursor below it."""
        if self._live is not None:
            self._live.stop()
            self._live = None
