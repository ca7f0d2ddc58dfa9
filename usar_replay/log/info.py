"""`usar info`: what a recording holds, in the spirit of ``ros2 bag info``, and whether it is whole.

A workflow over :func:`usar_replay.log.run.open_run`: it never fails on a damaged file, it says what
is damaged, how much is still readable and what to do; the CLI turns "not whole" into exit code 3.
By default the whole file is checked (every chunk decompressed, every CRC compared): a summary
can say ``complete`` over damaged data. ``quick=True`` trusts the summary.

Every string it prints from the file (topic and type names, settings, metadata, ``ros1.toml``'s
fields) is escaped (:mod:`usar_replay.core.safe_text`): a log is anyone's text.

The file's state (is the *file* whole?) and the mission's outcome (how did the *run* end?) are
two lines, because they answer different questions: a complete file can hold a mission that hit
its time limit.
"""

from __future__ import annotations

import os
import textwrap

from usar_replay.core import settings
from usar_replay.core.contract import SCENARIO_ATTACHMENT

# safe_line is also re-exported for record.py, which still imports it from here.
from usar_replay.core.safe_text import safe_line
from usar_replay.log import ros1_run
from usar_replay.log.run import Run, open_run

__all__ = ["SCENARIO_ATTACHMENT", "describe", "is_whole", "open_checked"]

WIDTH = 100
_LABEL = 15

_STATES = {
    "complete": "complete (closed and indexed)",
    "interrupted": "interrupted (closed and indexed, but the recording was stopped early)",
    "truncated": "INCOMPLETE (no usable summary or index: never closed, or damaged)",
    "corrupt": "CORRUPT (closed, but its data is damaged)",
    "unknown": "unknown (closed and indexed, but no usar status record)",
}

_OUTCOMES = {
    "done": "done (the mission finished)",
    "time_limit": "stopped at the time limit",
    "crashed": "the mission's code crashed",
    "hung": "the mission's code stopped responding",
    "build_failed": "the ROS 1 package did not build",
    "interrupted": "interrupted before the mission finished",
    "unknown": "not recorded in this log",
}


def open_checked(path: str | os.PathLike[str], *, quick: bool = False) -> Run:
    """Open ``path`` for ``usar info``: every chunk checked, or only the summary (``quick``)."""
    return open_run(path, check="summary" if quick else "full")


def is_whole(run: Run) -> bool:
    """A complete, undamaged file (``usar info`` exits 0 for it, 3 otherwise)."""
    return run.damage is None and run.file_state == "complete" and not run.problems


def _size(n: int) -> str:
    if n < 1024:
        return f"{n} B"
    value, unit = float(n), "B"
    for name in ("KiB", "MiB", "GiB"):
        value, unit = value / 1024, name
        if value < 1024:
            break
    return f"{value:.1f} {unit}"


def _field(label: str, text: str) -> list[str]:
    """``Label:  text``, wrapped to :data:`WIDTH` with the label's indent; a label as wide as
    the column (``Start read from``) keeps one space after its colon."""
    head = f"{label + ':':<{_LABEL}}" if len(label) + 2 <= _LABEL else f"{label}: "
    return textwrap.wrap(
        safe_line(text),
        WIDTH,
        initial_indent=head,
        subsequent_indent=" " * _LABEL,
        break_on_hyphens=False,
    ) or [head.rstrip()]


def _advice(run: Run) -> str:
    name = str(run.path)
    if run.file_state == "truncated":
        return f"`usar recover {name}` writes what it holds to an indexed log, marked interrupted"
    if run.damage is not None:
        return f"`usar recover {name} -o OUT.mcap` copies the readable messages to a new log"
    return ""


def _ros1_lines(run: Run, ros1: ros1_run.Ros1Run | None) -> list[str]:
    """What a ROS 1 run's package was: name, sha256, how started, nodes, build, output kept."""
    if ros1 is None:
        if not run.mission.module.startswith("ros1:"):
            return []
        # a run that ended before its package ran (build_failed): mission.toml only
        lines = _field("ROS 1 package", run.mission.module.removeprefix("ros1:"))
        lines += _field("sha256", run.mission.sha256 or "(not recorded)")
        lines += _field("Started with", run.mission.target)
        if run.outcome == "build_failed":
            lines += _field("Build", "failed: none of the package's nodes ran")
        return lines
    lines = _field("ROS 1 package", f"{ros1.package} ({ros1.path})" if ros1.path else ros1.package)
    lines += _field("sha256", ros1.sha256 or "(not recorded)")
    lines += _field("Started with", ros1.started_with)
    if ros1.start_source:
        lines += _field("Start read from", ros1.start_source)
    nodes = [f"{n.name} ({n.package}/{n.type})" if n.type else n.name for n in ros1.nodes]
    lines += _field("Nodes", ", ".join(nodes) or "(none started)")
    if ros1.replaced:
        gone = [f"{n.name} ({n.package}/{n.type})" for n in ros1.replaced]
        lines += _field("Replaced", "not started, usar stands in: " + ", ".join(gone))
    if ros1.build:  # a log recorded before the build's wall time left the log
        lines += _field("Build", ros1.build)
    lines += _field("Pacing", ros1.pacing)
    for tol in ros1.goal_tolerances:
        text = f"{tol.robot}: goal tolerances xy {tol.xy:g} m, yaw {tol.yaw:g} rad"
        text += f", from {tol.source}"
        lines += _field("move_base", text)
    if ros1.targets_replaced:
        lines.append("Targets replaced by the world's (the launch file set the course's):")
        for t in ros1.targets_replaced:
            by = "" if t.how == "name" else ", known by its value"
            lines.append(f"  {t.param} = target {t.target}{by}  ({t.source})"[:WIDTH])
    kept = ros1_run.node_outputs(run)
    if kept:
        text = f"{', '.join(kept)}: `usar log {run.path} --output [--node NAME]`"
        lines += _field("Node output", text)
    return lines


def describe(run: Run, *, quick: bool = False) -> str:
    """The human-readable report printed by ``usar info`` (every line within 100 columns)."""
    reader = run.reader
    state = _STATES.get(run.file_state, run.file_state)
    if run.file_state == "complete" and run.damage is None:
        state += "; summary trusted, data not checked" if quick else "; every CRC checked"
        if not quick and not reader.data_crc_recorded:
            state += " (chunks only: this log has no data CRC)"
    lines = _field("File", str(run.path))
    lines += _field("Size", f"{_size(reader.size_bytes)} in {reader.chunk_count} chunks")
    lines += _field("File state", state)
    if run.damage is not None:
        lines += _field("Damage", run.damage.describe())
    for problem in run.problems:
        lines += _field("Problem", problem)
    advice = _advice(run)
    if advice:
        lines += _field("What to do", advice)
    outcome = _OUTCOMES.get(run.outcome, run.outcome)
    if run.outcome_reason and run.outcome != "done":
        outcome += f": {safe_line(run.outcome_reason.splitlines()[0])}"
    lines += _field("Mission", outcome)
    lines += _field("Duration", f"{run.duration_s:.3f} s (sim time)")
    lines += _field("Start", f"{run.start_ns / 1e9:.3f} s")
    lines += _field("End", f"{run.end_ns / 1e9:.3f} s")
    lines += _field("Messages", str(reader.message_count))
    lines.append("Topics:")
    # a log's names are anyone's text: escaped before their widths are measured
    topics = [(safe_line(t.topic), safe_line(t.msgtype), t.count) for t in run.topics.values()]
    width = max((len(name) for name, _, _ in topics), default=0)
    twidth = max((len(msgtype) for _, msgtype, _ in topics), default=0)
    for name, msgtype, count in topics:
        lines.append(f"  {name:<{width}}  {msgtype:<{twidth}}  {count:>7}"[:WIDTH])
    if not topics:
        lines.append("  (none)")
    lines.append("Scenario:")
    if run.scenario is not None:
        lines += [f"  {line}"[:WIDTH] for line in run.scenario.summary().splitlines()]
    else:
        lines.append("  (no scenario attached)")
    ros1 = ros1_run.of(run)
    lines += _ros1_lines(run, ros1)
    rows = settings.describe(run.settings)
    if ros1 is not None and ros1.applied_settings:
        lines.append("Settings (those that applied to the ROS 1 run):")
        rows = [(k, v) for k, v in rows if ros1.applies(k)]
    else:
        lines.append("Settings:" if run.settings_recorded else "Settings (not recorded; defaults):")
    lines += [f"  {k} = {v}"[:WIDTH] for k, v in rows]
    if ros1 is not None:
        lines.append("Parameters the package's nodes read:")
        for p in ros1.parameters:
            value = p.value or "not set by usar"  # the launch file's value, or the node's default
            lines.append(f"  {p.name} = {value}  ({', '.join(p.read_by)})"[:WIDTH])
        if not ros1.parameters:
            lines.append("  (none)")
    if run.run_metadata:
        lines.append("Recorded with:")
        meta = sorted((k, v) for k, v in run.run_metadata.items() if k != "mission_settings")
        lines += [f"  {k} = {v}"[:WIDTH] for k, v in meta]  # mission_settings: under Settings
    # every string above came from the file (names, settings, ros1.toml, metadata): escaped
    # (those already escaped stay as they are), so none reaches a terminal raw
    return "\n".join(safe_line(line)[:WIDTH] if not line.isprintable() else line for line in lines)
