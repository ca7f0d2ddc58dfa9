"""Lines for people that fit 100 columns: a long message is wrapped, not left to run on.

Why a module of its own: every command prints sentences that carry paths and reasons of any
length (the log is incomplete because ..., recovered from PATH into PATH); a terminal of 100
columns must show each without a line running past the edge, and the tests check that.
"""

from __future__ import annotations

import sys
import textwrap
from typing import TextIO

__all__ = ["WIDTH", "incomplete_note", "print_wrapped", "wrap"]

WIDTH = 100
"""The widest line a command prints."""


def wrap(text: str, width: int = WIDTH, indent: str = "  ") -> list[str]:
    """``text`` as lines of at most ``width`` columns, the continuation lines indented; words
    (and paths) are broken only when one is longer than a line."""
    return textwrap.wrap(
        text,
        width=width,
        subsequent_indent=indent,
        break_on_hyphens=False,
        break_long_words=True,
    ) or [""]


def print_wrapped(text: str, file: TextIO | None = None, width: int = WIDTH) -> None:
    """Print ``text`` wrapped to ``width`` (stdout unless ``file``)."""
    print("\n".join(wrap(text, width)), file=file or sys.stdout)


def incomplete_note(path: str, problem: str, done: str) -> str:
    """The one stderr line of a command that worked through a damaged log (exit 3).

    It stays one line (scripts, and the README's contract, read it as the command's one note)
    and names the path as given; to fit :data:`WIDTH` columns the problem is shortened, from
    all of it down to how many messages were read (the table or ``usar info`` says the rest).
    Only a path too long for a line makes the line longer."""
    import re

    from usar_replay.core.safe_text import safe_line

    path, problem = safe_line(path), safe_line(problem)  # the problem may quote a log's names
    tail = f"{done} as far as it goes"
    candidates = [f"usar: {path}: the log is incomplete ({problem}); {tail}"]
    timed = re.search(r"read (\d+) messages up to sim time ([\d.]+) s", problem)
    if timed is not None:  # where the readable part ends, in fewer words
        short = f"{timed[1]} messages, to {timed[2]} s"
        candidates.append(f"usar: {path}: the log is incomplete ({short}); {tail}")
    found = re.search(r"read \d+ messages", problem)
    if found is not None:
        candidates.append(f"usar: {path}: the log is incomplete ({found[0]}); {tail}")
    return next((c for c in candidates if len(c) <= WIDTH), candidates[-1])
