"""The ``usar`` argument parser: one ``usar: error:`` line for a bad command line, the argument
types several commands share, and the assembly of every command's sub-parser.

Why apart from the commands: building the parser must stay cheap (``usar --help`` imports no
back end), so each command module adds its own options here and imports its work lazily.
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from usar_replay import __version__
from usar_replay.cli.commands import (
    batch,
    code,
    doctor,
    echo,
    grade,
    gradescope,
    info,
    log,
    record,
    recover,
    replay,
    report,
    scenario,
    view,
)
from usar_replay.cli.parser_parts import UsageParser

if TYPE_CHECKING:
    pass

__all__ = ["COMMANDS", "build_parser"]

COMMANDS = (
    record, replay, grade, report, batch, gradescope, code, view, echo, log, scenario, info,
    recover, doctor,
)
"""The commands, in the order ``usar --help`` lists them."""


def build_parser() -> argparse.ArgumentParser:
    """The ``usar`` parser: the global options, then each command's own (its module's
    ``add_parser``), in the order ``usar --help`` lists them."""
    parser = UsageParser(
        prog="usar",
        description=(
            "Run, record, replay, grade and view the two-robot US&R mission "
            "(ENPM809Y 'US&R Simplified') without ROS."
        ),
        epilog=(
            "Exit codes: 0 ok, 1 a check failed, 2 usage error, 3 incomplete or corrupt log, "
            "4 the mission's code failed, 130/143/129 interrupted by SIGINT/SIGTERM/SIGHUP."
        ),
    )
    parser.add_argument("--version", action="version", version=f"usar-replay {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    for command in COMMANDS:
        command.add_parser(sub)
    return parser
