"""What the command modules share in their parsers: a parser whose bad command line is one
``usar: error:`` line, the argument types (seconds, ports, addresses) and the option groups
several commands take (the mission's options, the grade's outputs).
"""

from __future__ import annotations

import argparse
import math
import sys
from typing import NoReturn

from usar_replay.cli.exits import EXIT_USAGE
from usar_replay.core.limits import FLAGS, RunLimits

__all__ = [
    "UsageParser",
    "address",
    "grade_outputs",
    "limit_options",
    "mission_options",
    "port",
    "positive_seconds",
]


class UsageParser(argparse.ArgumentParser):
    """argparse, but a bad command line is one ``usar: error:`` line and a hint (not a usage
    block), like every other user error."""

    def error(self, message: str) -> NoReturn:
        print(f"usar: error: {message}; see `{self.prog} --help`", file=sys.stderr)
        raise SystemExit(EXIT_USAGE)


def positive_seconds(text: str) -> float:
    """``--max-sim-time``: a finite number of seconds above 0 (nan, 0 and -1 are refused)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of seconds") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"{text!r}: expected seconds above 0, e.g. 60")
    return value


def port(text: str) -> int:
    """A TCP port number for the parser (1-65535)."""
    try:
        port = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a port number (1-65535)") from None
    if not 1 <= port <= 65535:
        raise argparse.ArgumentTypeError(f"{port} is not a port number (1-65535)")
    return port


def address(text: str) -> str:
    """An IP address for the parser (what ``rerun --bind`` takes)."""
    import ipaddress

    try:
        return str(ipaddress.ip_address(text))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an IP address") from None


def mission_options(p: argparse.ArgumentParser, *, replay: bool) -> None:
    p.add_argument(
        "--mission",
        metavar="TARGET",
        help=(
            "mission code: a .py file or module:function that creates the nodes "
            + ("(default: the one the log recorded)" if replay else "(default: builtin)")
        ),
    )
    p.add_argument(
        "--set",
        action="append",
        metavar="NAME=VALUE",
        help="a setting, e.g. detector.dictionary=DICT_5X5_50 or mission.settle_frames=3",
    )
    p.add_argument("--settings", metavar="TOML", help="settings from [record]/[mission]/[detector]")
    limit_options(p, "replay" if replay else "record")


def limit_options(
    p: argparse.ArgumentParser, command: str, defaults: RunLimits | None = None
) -> None:
    """The run's limits ``command`` takes, made from the one table of them
    (:data:`usar_replay.core.limits.FLAGS`), ``defaults`` shown in the help (the command's:
    ``usar batch`` gives each mission 30 CPU minutes); ``--limits FILE`` reads them from a
    ``[limits]`` table, and a flag given wins over it. :func:`usar_replay.cli.options.run_limits`
    reads them back."""
    base = defaults or RunLimits()
    group = p.add_argument_group("the run's limits (docs/batch.md, \"A run's limits\")")
    group.add_argument(
        "--limits",
        metavar="TOML",
        dest="limits_file",
        help="the run's limits from a [limits] table (docs/batch.md); a flag given wins",
    )
    for row in FLAGS:
        if command not in row.commands:
            continue
        zero = f"; 0: {row.zero}" if row.zero else ""
        group.add_argument(
            row.flag,
            type=row.kind,
            default=None,
            dest=row.dest,
            metavar=row.metavar,
            help=f"{row.help} ({_shown(getattr(base, row.name))}{zero})",
        )
    p.set_defaults(limits_base=base)


def _shown(value: float) -> str:
    """A default as the help says it: ``10``, ``0.5``, ``3600``."""
    return f"{value:g}"


def class_run_options(p: argparse.ArgumentParser) -> None:
    """The settings, hard stop and thresholds a class's runs share (``usar batch`` and ``usar
    gradescope`` grade a team the same way, so they take the same words for it)."""
    p.add_argument("--settings", metavar="TOML", help="settings from [record]/[mission]/[detector]")
    p.add_argument("--set", action="append", metavar="NAME=VALUE", help="a setting (as record)")
    p.add_argument("--max-sim-time", type=float, metavar="S", help="hard stop in sim seconds")
    p.add_argument(
        "--thresholds", metavar="TOML", help="override rubric thresholds ([thresholds] table)"
    )


def class_grade_options(p: argparse.ArgumentParser) -> None:
    """How a class's runs are confined and graded (``usar batch`` and ``usar gradescope``): one
    declaration, so the warning of ``--no-sandbox`` and Gradescope's visibilities are the same
    words in both."""
    p.add_argument(
        "--no-sandbox",
        action="store_true",
        help="run missions without bwrap and the guard: a mission can then read every file "
        "usar can, the hidden worlds' key included (only for code you trust)",
    )
    p.add_argument(
        "--visibility",
        choices=["visible", "hidden", "after_due_date", "after_published"],
        default="visible",
        help="Gradescope visibility of the tests (visible)",
    )
    p.add_argument(
        "--code",
        action="store_true",
        help="also grade each team's code submission (usar code; docs/code-rubric.md)",
    )
    p.add_argument(
        "--code-template",
        metavar="DIR",
        help="with --code: the course template, boilerplate for the code grade",
    )


def grade_outputs(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--thresholds", metavar="TOML", help="override rubric thresholds ([thresholds] table)"
    )
    p.add_argument("--json", metavar="PATH", help="write the grade as JSON")
    p.add_argument("--junit", metavar="PATH", help="write JUnit XML (a test case per rubric line)")
    p.add_argument("--csv", metavar="PATH", help="write CSV (a row per recording)")
    p.add_argument(
        "--overwrite", action="store_true", help="replace existing --json/--junit/--csv files"
    )
