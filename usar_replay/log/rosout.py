"""`usar log`: the mission's own log lines (``/rosout``), one line per entry, as ROS 2 prints them.

Each entry is ``[LEVEL] [sim time] [node]: text``, the layout of ROS 2's console output
(``RCUTILS_CONSOLE_OUTPUT_FORMAT``'s default), with the message's log time = its sim time in
seconds (the clock of ``usar grade``'s 'at' column and ``usar view``'s timeline). An entry
longer than the width, or of several lines (a traceback), goes on over indented lines, so every
line fits and ``grep`` on a node or a level still finds each entry's first line.

Filters: a lowest level (``--level WARN`` keeps WARN, ERROR and FATAL, as ``--log-level`` does
in ROS 2), node names (the Log message's ``name``), a time window. A node that never logged is
an error naming the nodes that did, after the lines that matched.
"""

from __future__ import annotations

import textwrap
from collections.abc import Iterator
from dataclasses import dataclass

from usar_replay.core import contract, msgs
from usar_replay.core.errors import UsageError
from usar_replay.core.msg_text import WIDTH
from usar_replay.core.safe_text import safe, safe_line
from usar_replay.log.run import Run

__all__ = ["LEVELS", "LogRequest", "entry_lines", "level_name", "level_value", "lines"]

LEVELS = {
    msgs.Log.DEBUG: "DEBUG",
    msgs.Log.INFO: "INFO",
    msgs.Log.WARN: "WARN",
    msgs.Log.ERROR: "ERROR",
    msgs.Log.FATAL: "FATAL",
}
"""rcl_interfaces/Log's levels and the names ROS 2 prints for them."""

_INDENT = "    "


@dataclass(frozen=True, slots=True)
class LogRequest:
    """Which entries: the lowest level, the nodes (empty: all), a window in log-time ns."""

    level: int = 0
    nodes: tuple[str, ...] = ()
    since_ns: int | None = None
    until_ns: int | None = None
    """Included: an entry at exactly this time is printed."""
    width: int = WIDTH


def level_name(level: int) -> str:
    """``20`` -> ``INFO``; a level rcl does not define is printed as its number."""
    return LEVELS.get(level, str(level))


def level_value(name: str) -> int:
    """``warn``/``WARNING`` -> 30 (:class:`ValueError` for a name that is not a level)."""
    key = name.strip().upper()
    key = {"WARNING": "WARN", "CRITICAL": "FATAL"}.get(key, key)
    for value, text in LEVELS.items():
        if text == key:
            return value
    raise ValueError(f"{name!r} is not a level; one of {', '.join(LEVELS.values())}")


def entry_lines(t_ns: int, entry: msgs.Log, width: int = WIDTH) -> list[str]:
    """One entry as ``[INFO] [12.350] [explorer]: text``, wrapped to ``width``."""
    head = f"[{level_name(entry.level)}] [{t_ns / 1e9:.3f}] [{safe_line(entry.name)}]: "
    out: list[str] = []
    # the mission's text: control characters escaped, only its line breaks kept
    for i, part in enumerate(safe(entry.msg.expandtabs(4)).splitlines() or [""]):
        out += textwrap.wrap(
            (head if i == 0 else _INDENT) + part,
            width,
            subsequent_indent=_INDENT,
            break_on_hyphens=False,
            drop_whitespace=True,
        ) or [(head if i == 0 else _INDENT).rstrip()]
    return out


def lines(run: Run, request: LogRequest) -> Iterator[str]:
    """The lines of every ``/rosout`` entry the request keeps, in log-time order.

    A log without ``/rosout`` yields nothing (the mission logged nothing). After the last line,
    a requested node that never logged raises :class:`UsageError` naming the nodes that did.
    """
    if contract.ROSOUT not in run.topics:
        if request.nodes and run.damage is None:
            raise UsageError(f"{run.path}: no node logged anything (no {contract.ROSOUT})")
        return
    seen: set[str] = set()
    wanted = {n.lstrip("/") for n in request.nodes}  # a ROS 1 name (/explorer) finds it too
    since, until = request.since_ns, request.until_ns
    for _topic, entry, t in run.reader.decoded([contract.ROSOUT]):
        if not isinstance(entry, msgs.Log):
            continue
        seen.add(entry.name)
        if (since is not None and t < since) or (until is not None and t > until):
            continue
        if entry.level < request.level or (wanted and entry.name.lstrip("/") not in wanted):
            continue
        yield from entry_lines(t, entry, request.width)
    seen_names = {n.lstrip("/") for n in seen}
    missing = [n for n in request.nodes if n.lstrip("/") not in seen_names]
    if missing:
        raise UsageError(
            f"{run.path}: no node {missing[0]} in {contract.ROSOUT}; the nodes that logged: "
            + (", ".join(sorted(seen)) or "none")
        )
