"""The `usar` command: arguments, messages to people, exit codes.

Exit codes (the same for every subcommand):

* 0 - done; for grading: every required rubric line passed.
* 1 - a rubric line or the replay comparison failed.
* 2 - usage error: bad option, bad scenario file, a command not built yet.
* 3 - the log is incomplete or corrupt (what could be read was still used, and said so).
* 130 - interrupted by Ctrl-C (a recording is still closed and readable).

User errors (:class:`usar_replay.errors.UsarError`) are printed as one line, ``usar: error: ...``,
without a traceback; anything else is a bug and raises.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence

from usar_replay import __version__
from usar_replay.errors import NotBuiltYet, UsarError

__all__ = ["main"]

EXIT_OK = 0
EXIT_FAIL = 1
EXIT_USAGE = 2
EXIT_INCOMPLETE = 3
EXIT_INTERRUPTED = 130


def _cmd_info(args: argparse.Namespace) -> int:
    from usar_replay.info import describe, read_info

    worst = EXIT_OK
    for i, path in enumerate(args.files):
        info = read_info(path)
        if i:
            print()
        print(describe(info))
        if not info.complete:
            worst = EXIT_INCOMPLETE
    return worst


def _not_built(name: str) -> Callable[[argparse.Namespace], int]:
    def run(args: argparse.Namespace) -> int:
        raise NotBuiltYet(
            f"`usar {name}` is not built yet in usar-replay {__version__}; "
            "see the README for what works today"
        )

    return run


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="usar",
        description=(
            "Run, record, replay, grade and view the two-robot US&R mission "
            "(ENPM809Y 'US&R Simplified') without ROS."
        ),
        epilog="Exit codes: 0 ok, 1 a check failed, 2 usage error, 3 incomplete or corrupt log.",
    )
    parser.add_argument("--version", action="version", version=f"usar-replay {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    p = sub.add_parser("record", help="run the mission in pybullet and record it to MCAP")
    p.set_defaults(func=_not_built("record"))

    p = sub.add_parser("replay", help="re-run detector/tf/follower from a log and compare")
    p.add_argument("file")
    p.set_defaults(func=_not_built("replay"))

    p = sub.add_parser("grade", help="grade recordings against the course rubric")
    p.add_argument("files", nargs="+")
    p.set_defaults(func=_not_built("grade"))

    p = sub.add_parser("view", help="show a recording's timeline in the rerun viewer")
    p.add_argument("file")
    p.set_defaults(func=_not_built("view"))

    p = sub.add_parser("info", help="summarise a recording (topics, counts, scenario, status)")
    p.add_argument("files", nargs="+", metavar="FILE", help="one or more .mcap files")
    p.set_defaults(func=_cmd_info)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``usar`` console script; returns the process exit code."""
    parser = _parser()
    args = parser.parse_args(argv)
    try:
        code: int = args.func(args)
    except UsarError as err:
        print(f"usar: error: {err}", file=sys.stderr)
        return err.exit_code
    except KeyboardInterrupt:
        print("usar: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:
        return EXIT_OK
    return code


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
