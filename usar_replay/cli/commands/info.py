"""`usar info`: a recording's state, outcome, topics and settings, its CRCs checked."""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING

from usar_replay.cli.exits import EXIT_INCOMPLETE, EXIT_OK
from usar_replay.core.errors import UsarError
from usar_replay.core.safe_text import safe

if TYPE_CHECKING:
    pass

__all__ = ["add_parser", "run"]


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """This command's sub-parser and options (``usar COMMAND --help`` shows them)."""
    p = sub.add_parser("info", help="summarise and check a recording (topics, state, outcome)")
    p.add_argument("files", nargs="+", metavar="FILE", help="one or more .mcap files")
    p.add_argument(
        "--quick", action="store_true", help="trust the summary: do not check the data's CRCs"
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from usar_replay.log.info import describe, is_whole, open_checked

    worst = EXIT_OK
    for i, path in enumerate(args.files):
        try:
            run = open_checked(path, quick=args.quick)
        except UsarError as err:  # one bad path among several is one line, not the end
            print(f"usar: error: {safe(str(err))}", file=sys.stderr)
            worst = max(worst, err.exit_code)
            continue
        if i:
            print()
        print(describe(run, quick=args.quick))
        if not is_whole(run):
            worst = max(worst, EXIT_INCOMPLETE)
    return worst
