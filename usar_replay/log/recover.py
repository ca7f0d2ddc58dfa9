"""`usar recover`: the readable part of a damaged log, written as a new, whole log.

Why: a recording killed by SIGKILL (or a power cut, or a full disk) leaves ``NAME.mcap.part``:
chunks of messages with no summary or index, which the ``mcap`` library and most viewers refuse.
A log with a damaged chunk is refused by graders. Everything intact in them is still worth
having, so this copies every message of every intact chunk, the scenario and the run's settings
into a new log, closed and indexed as usual and marked ``interrupted`` (with what happened in its
reason), which every usar command and every MCAP tool can read.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from usar_replay.core import contract
from usar_replay.core.errors import UsageError
from usar_replay.core.outfiles import check_output
from usar_replay.log import bag

__all__ = ["Recovered", "default_output", "recover"]


@dataclass(frozen=True, slots=True)
class Recovered:
    """What :func:`recover` wrote."""

    source: Path
    output: Path
    messages: int
    messages_total: int | None
    last_time_ns: int
    damage: str

    def describe(self) -> str:
        """One line for a person."""
        of = "" if self.messages_total is None else f" of {self.messages_total}"
        return (
            f"recovered {self.messages}{of} messages (up to sim time "
            f"{self.last_time_ns / 1e9:.3f} s) from {self.source} into {self.output}, "
            "marked interrupted"
        )


def default_output(source: Path) -> Path:
    """``X.mcap.part`` -> ``X.mcap`` (when free); otherwise ``X.recovered.mcap`` beside it."""
    if source.name.endswith(".part"):
        plain = source.with_name(source.name.removesuffix(".part"))
        if not plain.exists():
            return plain
        source = plain
    return source.with_name(f"{source.stem}.recovered{source.suffix or '.mcap'}")


def recover(
    source: str | os.PathLike[str],
    output: str | os.PathLike[str] | None = None,
    *,
    overwrite: bool = False,
) -> Recovered:
    """Copy the readable messages of ``source`` into a new log at ``output``.

    Raises :class:`UsageError` when ``source`` is whole (nothing to recover) or holds no readable
    message, and when ``output`` exists (without ``overwrite``) or is ``source``.
    """
    src = Path(source)
    reader = bag.BagReader(src, check="full")
    if reader.damage is None and reader.has_summary:
        raise UsageError(f"{src}: the log is whole; there is nothing to recover")
    out = Path(output) if output is not None else default_output(src)
    check_output(out, overwrite=overwrite, inputs=[src], option="-o")
    count, last = 0, 0
    problem = reader.damage.describe() if reader.damage is not None else ""
    # X.mcap.part -> X.mcap: the writer's own .part would be the source, so write beside it
    # under a hidden name and give it the final name at the end (never over an existing file)
    staging = out.with_name(f".{out.name}.recovering")
    with bag.BagWriter(staging) as w:
        for name, data in sorted(reader.attachments.items()):
            media = "application/toml" if name.endswith(".toml") else "application/octet-stream"
            w.add_attachment(name, media, data, reader.start_ns)
        for name, record in sorted(reader.metadata.items()):
            if name != contract.STATUS_METADATA:
                w.add_metadata(name, record)
        for m in reader.messages(decode_messages=False):
            w.write_raw(m.topic, m.msgtype, m.data, m.log_time_ns)
            count, last = count + 1, m.log_time_ns
        problem = reader.damage.describe() if reader.damage is not None else problem
        w.close("interrupted", reason=f"recovered by `usar recover` from {src.name}: {problem}")
    if count == 0:
        staging.unlink(missing_ok=True)
        raise UsageError(f"{src}: no message could be recovered ({problem})")
    try:
        if overwrite:
            os.replace(staging, out)
        else:
            os.link(staging, out)
            staging.unlink()
    except FileExistsError:
        staging.unlink(missing_ok=True)
        raise UsageError(f"-o {out}: appeared while recovering; it was left as it is") from None
    total = reader.damage.messages_total if reader.damage is not None else None
    return Recovered(src, out, count, total, last, problem)
