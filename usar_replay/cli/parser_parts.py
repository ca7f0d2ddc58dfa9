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

__all__ = [
    "UsageParser",
    "address",
    "grade_outputs",
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
    p.add_argument(
        "--tick-timeout",
        type=float,
        default=10.0,
        metavar="S",
        help="wall seconds a tick's callbacks may take before the mission is 'hung' (10)",
    )
    p.add_argument(
        "--mission-memory",
        type=int,
        default=4096,
        metavar="MIB",
        help="memory limit of the mission process in MiB (4096; 0: none)",
    )
    p.add_argument(
        "--max-log-mib",
        type=int,
        default=2048,
        metavar="MIB",
        help="byte budget of the run's log in MiB; past it the run is 'refused' (2048; 0: none)",
    )
    p.add_argument(
        "--wall-limit",
        type=float,
        default=3600.0,
        metavar="S",
        help="wall seconds for the whole run; past it 'wall_limit' (3600; 0: none)",
    )
    run_limit_options(p)


def run_limit_options(p: argparse.ArgumentParser) -> None:
    """The limits of a run as a whole (its cgroups and its folder; docs/batch.md)."""
    p.add_argument(
        "--run-memory",
        type=int,
        default=3072,
        metavar="MIB",
        help="memory of the whole run, its tmpfs files included, MiB; past it 'out_of_memory' "
        "(3072; 0: none)",
    )
    p.add_argument(
        "--processes",
        type=int,
        default=256,
        metavar="N",
        help="processes and threads of the run; reaching it: 'refused' (256)",
    )
    p.add_argument(
        "--run-folder",
        type=int,
        default=512,
        metavar="MIB",
        help="size of the run's writable folder, MiB; filling it: 'refused' (512; 0: no limit)",
    )
    p.add_argument(
        "--max-holds",
        type=int,
        default=20,
        metavar="N",
        help="ROS 1 ticks held for a node's shutdown; past it 'hung' (20; 0: no budget)",
    )
    p.add_argument(
        "--hold-wall",
        type=float,
        default=30.0,
        metavar="S",
        help="wall seconds the ROS 1 shutdown holds may take together; past it 'hung' "
        "(30; 0: no budget)",
    )
    p.add_argument(
        "--max-capped",
        type=int,
        default=600,
        metavar="N",
        help="ROS 1 ticks that reach their wall cap; past it 'hung' (600; 0: no budget)",
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
