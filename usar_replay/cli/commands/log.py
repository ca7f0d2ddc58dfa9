"""`usar log`: the mission's log lines (``/rosout``) with sim time, level and node."""

from __future__ import annotations

import argparse

from usar_replay.cli import window

__all__ = ["add_parser", "run"]


def _level(text: str) -> int:
    from usar_replay.log.rosout import level_value

    try:
        return level_value(text)
    except ValueError as err:
        raise argparse.ArgumentTypeError(str(err)) from None


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """This command's sub-parser and options (``usar COMMAND --help`` shows them)."""
    p = sub.add_parser(
        "log",
        help="print the mission's log lines (/rosout): sim time, level, node",
        description=(
            "Print every /rosout entry of FILE as `[LEVEL] [sim time] [node]: text`, the way "
            "ROS 2 prints its console, one entry per line (long ones go on indented)."
        ),
    )
    p.add_argument("file", metavar="FILE")
    p.add_argument(
        "--level",
        type=_level,
        default=0,
        metavar="LEVEL",
        help="this level and above: DEBUG, INFO, WARN, ERROR or FATAL",
    )
    p.add_argument(
        "--node",
        action="append",
        default=[],
        metavar="NAME",
        help="only this node's lines (the name it logs under; repeat for several)",
    )
    window.add_window(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from usar_replay.log.rosout import LogRequest, lines
    from usar_replay.log.run import open_run

    since, until = window.window_ns(args)
    run = open_run(args.file)
    request = LogRequest(args.level, tuple(args.node), since, until)
    window.write_lines(lines(run, request))
    return window.finish(run.problem(), run.path, "read")
