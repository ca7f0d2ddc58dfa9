"""What ``usar echo`` and ``usar log`` share: the time window (``--since``/``--until``), the
note on a damaged log, and a quiet end when the reader of the output goes away (``| head``).

The window is sim time in seconds, the clock ``usar grade`` prints in its 'at' column and
``usar view`` shows on its timeline (the sim clock starts at 1 s, so a log starts at 1.000):
a grade line's time can be typed here as it is.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from collections.abc import Iterable

from usar_replay.cli.exits import EXIT_INCOMPLETE, EXIT_OK
from usar_replay.cli.textout import incomplete_note
from usar_replay.core.errors import UsageError

__all__ = ["add_window", "finish", "window_ns", "write_lines"]

HELP = "sim time (s), the clock of `usar grade`'s 'at' and `usar view`; a run starts at 1.000"


def _seconds(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of seconds") from None
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"{text!r}: expected sim seconds, 0 or more, e.g. 12.3")
    return value


def add_window(p: argparse.ArgumentParser) -> None:
    """``--since S`` and ``--until S`` (both included)."""
    p.add_argument("--since", type=_seconds, metavar="S", help=f"from this {HELP}")
    p.add_argument("--until", type=_seconds, metavar="S", help="up to this sim time (included)")


def window_ns(args: argparse.Namespace) -> tuple[int | None, int | None]:
    """The window in log-time nanoseconds (:class:`UsageError` when it is empty)."""
    since = None if args.since is None else round(args.since * 1e9)
    until = None if args.until is None else round(args.until * 1e9)
    if since is not None and until is not None and until < since:
        raise UsageError(f"--until {args.until} is before --since {args.since}")
    return since, until


def write_lines(lines: Iterable[str]) -> int:
    """Write ``lines`` to stdout; how many. A reader that went away (``| head``) ends it
    quietly: stdout is pointed at /dev/null so Python's own flush at exit cannot complain."""
    count = 0
    out = sys.stdout
    try:
        for line in lines:
            out.write(line + "\n")
            count += 1
        out.flush()
    except BrokenPipeError:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, out.fileno())
        os.close(devnull)
        raise
    return count


def finish(problem: str, path: object, verb: str) -> int:
    """Exit 0, or 3 with one line on stderr when the log was not whole (``problem``): the
    note grade and replay print (:func:`usar_replay.cli.textout.incomplete_note`)."""
    if not problem:
        return EXIT_OK
    print(incomplete_note(str(path), problem, verb), file=sys.stderr)
    return EXIT_INCOMPLETE
