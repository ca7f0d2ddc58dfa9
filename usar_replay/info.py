"""`usar info`: what a recording holds, in the spirit of ``ros2 bag info``.

A workflow over :mod:`usar_replay.bag`: it never fails on a damaged file, it says how far the file
could be read; the CLI turns "not complete" into exit code 3.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

from usar_replay import bag
from usar_replay.errors import InvalidScenario

__all__ = ["SCENARIO_ATTACHMENT", "LogInfo", "describe", "read_info"]

SCENARIO_ATTACHMENT = "scenario.toml"


@dataclass(frozen=True, slots=True)
class LogInfo:
    """What is known about one log, ready to print or to turn into JSON."""

    path: str
    size_bytes: int
    status: str
    complete: bool
    damage: str
    start_ns: int
    end_ns: int
    message_count: int
    topics: tuple[bag.TopicInfo, ...]
    scenario_summary: str
    run_settings: tuple[tuple[str, str], ...]

    @property
    def duration_s(self) -> float:
        return max(self.end_ns - self.start_ns, 0) / 1e9


def read_info(path: str | os.PathLike[str]) -> LogInfo:
    """Open ``path`` and collect its :class:`LogInfo` (raises ``NotAnMcapFile`` for non-logs)."""
    reader = bag.BagReader(path)
    scenario_summary = "(no scenario attached)"
    text = reader.attachments.get(SCENARIO_ATTACHMENT)
    if text is not None:
        scenario_summary = _scenario_summary(text.decode("utf-8", errors="replace"))
    return LogInfo(
        path=str(reader.path),
        size_bytes=reader.size_bytes,
        status=reader.status,
        complete=reader.complete,
        damage=reader.damage.describe() if reader.damage else "",
        start_ns=reader.start_ns,
        end_ns=reader.end_ns,
        message_count=reader.message_count,
        topics=tuple(reader.topics.values()),
        scenario_summary=scenario_summary,
        run_settings=tuple(sorted(reader.metadata.get(bag.RUN_METADATA, {}).items())),
    )


def _scenario_summary(text: str) -> str:
    from usar_replay import scenario  # local: keeps `usar info` usable on logs without one

    try:
        return scenario.from_toml(text, source=SCENARIO_ATTACHMENT).summary()
    except InvalidScenario as err:
        return f"(attached scenario is invalid: {err})"


def _size(n: int) -> str:
    if n < 1024:
        return f"{n} B"
    value = float(n)
    for unit in ("KiB", "MiB", "GiB"):
        value /= 1024
        if value < 1024 or unit == "GiB":
            break
    return f"{value:.1f} {unit}"


def describe(info: LogInfo) -> str:
    """The human-readable report printed by ``usar info``."""
    state = {
        "complete": "complete",
        "interrupted": "interrupted (closed and indexed, but the run was stopped early)",
        "truncated": "INCOMPLETE (no summary: truncated or not closed)",
    }.get(info.status, info.status)
    lines = [
        f"Files:         {info.path}",
        f"Size:          {_size(info.size_bytes)}",
        f"Status:        {state}",
    ]
    if info.damage:
        lines.append(f"Damage:        {info.damage}")
    lines += [
        f"Duration:      {info.duration_s:.3f} s (sim time)",
        f"Start:         {info.start_ns / 1e9:.3f} s",
        f"End:           {info.end_ns / 1e9:.3f} s",
        f"Messages:      {info.message_count}",
        "Topics:",
    ]
    width = max((len(t.topic) for t in info.topics), default=0)
    twidth = max((len(t.msgtype) for t in info.topics), default=0)
    for t in info.topics:
        lines.append(f"  {t.topic:<{width}}  {t.msgtype:<{twidth}}  {t.count:>7}")
    if not info.topics:
        lines.append("  (none)")
    lines.append("Scenario:")
    lines += [f"  {line}" for line in info.scenario_summary.splitlines()]
    if info.run_settings:
        lines.append("Run settings:")
        lines += [f"  {k} = {v}" for k, v in info.run_settings]
    return "\n".join(lines)
