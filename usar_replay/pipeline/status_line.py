"""The log line the record status line shows, when several nodes log (a ROS 1 launch file).

Why not simply the last ``/rosout`` line: a node that waits says so again and again (a
follower's throttled "waiting for the explorer's markers" every second), and each repeat hid
the other node's progress for the whole search. So a line that only repeats its node's
previous line does not take the status line over: it shows the most recent *new* line of any
node, prefixed with the node's name once more than one node has logged. A terminal shows more:
one line per node under the status line (:meth:`NodeLines.per_node`,
:mod:`usar_replay.cli.status_display`), so each node's progress stays in view.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from usar_replay.core import msgs

__all__ = ["NodeLines"]


@dataclass(slots=True)
class NodeLines:
    """Each node's last line and the most recent new one (see the module doc)."""

    last: dict[str, str] = field(default_factory=dict)
    """Node name -> its last line."""
    shown: tuple[str, str] = ("", "")
    """(node, text) of the most recent line that was new for its node."""

    def note(self, entry: msgs.Log) -> None:
        node = entry.name.lstrip("/")
        text = entry.msg.splitlines()[0] if entry.msg else ""
        if self.last.get(node) != text:
            self.shown = (node, text)
        self.last[node] = text

    def per_node(self) -> tuple[tuple[str, str], ...]:
        """(node, its last line) for every node that logged, in the order they first did."""
        return tuple(self.last.items())

    def status(self) -> str:
        node, text = self.shown
        return f"[{node}] {text}" if len(self.last) > 1 and node else text
