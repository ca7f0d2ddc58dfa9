"""`usar log`: the mission's log lines (``/rosout``) with sim time, level and node; with
``--output``, a ROS 1 run's nodes' own stdout and stderr (``output="screen"``), as kept in the
log."""

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
    p.add_argument(
        "--output",
        action="store_true",
        help="a ROS 1 run's nodes' stdout and stderr (output=\"screen\") instead of /rosout",
    )
    window.add_window(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from usar_replay.log.rosout import LogRequest, lines
    from usar_replay.log.run import open_run

    if args.output:
        return _output(args)
    since, until = window.window_ns(args)
    run = open_run(args.file)
    request = LogRequest(args.level, tuple(args.node), since, until)
    window.write_lines(lines(run, request))
    return window.finish(run.problem(), run.path, "read")


def _output(args: argparse.Namespace) -> int:
    """``--output``: each node's kept stdout and stderr (no sim times: a node's print has
    none); ``--level``, ``--since`` and ``--until`` filter /rosout entries only."""
    from usar_replay.core.errors import UsageError
    from usar_replay.log.ros1_run import node_output_lines
    from usar_replay.log.run import open_run

    if args.level or args.since is not None or args.until is not None:
        raise UsageError(
            "--output shows the nodes' output as printed: no --level, --since, --until"
        )
    run = open_run(args.file)
    window.write_lines(node_output_lines(run, tuple(args.node)))
    return window.finish(run.problem(), run.path, "read")
