"""Lines for people that fit 100 columns: a long message is wrapped, not left to run on.

Why a module of its own: every command prints sentences that carry paths and reasons of any
length (the log is incomplete because ..., recovered from PATH into PATH); a terminal of 100
columns must show each without a line running past the edge, and the tests check that.
"""

from __future__ import annotations

import sys
import textwrap
from typing import TextIO

__all__ = ["WIDTH", "print_wrapped", "wrap"]

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
