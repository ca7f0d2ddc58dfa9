"""`usar echo`: one topic's messages from a log, as ``ros2 topic echo`` prints them."""

from __future__ import annotations

import argparse
import sys

from usar_replay.cli import window

__all__ = ["add_parser", "run"]


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """This command's sub-parser and options (``usar COMMAND --help`` shows them)."""
    p = sub.add_parser(
        "echo",
        help="print a topic's messages, like `ros2 topic echo`",
        description=(
            "Print the messages of TOPIC in FILE, one YAML-like block per message (its sim "
            "time first, `---` after), within 100 columns. Long arrays are elided and byte "
            "fields (an image's data) shown as their size unless --full-length."
        ),
    )
    p.add_argument("file", metavar="FILE")
    p.add_argument("topic", metavar="TOPIC", help="e.g. /explorer/cmd_vel (`usar info` lists them)")
    window.add_window(p)
    p.add_argument(
        "--fields",
        metavar="A.B,C",
        help="only these fields (dotted paths, a list item by index: transforms.0.child_frame_id)",
    )
    p.add_argument(
        "--full-length",
        action="store_true",
        help="print every array item and every byte (default: `data: <6,512 bytes>`)",
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from usar_replay.log.echo import EchoRequest, blocks
    from usar_replay.log.run import open_run

    since, until = window.window_ns(args)
    fields = tuple(f.strip() for f in (args.fields or "").split(",") if f.strip())
    run = open_run(args.file)
    request = EchoRequest(args.topic, since, until, fields, full=args.full_length)
    printed = window.write_lines(line for block in blocks(run, request) for line in block)
    if not printed and (since is not None or until is not None):
        print(
            f"usar: no message on {args.topic} in that window (the log spans "
            f"{run.start_ns / 1e9:.3f}-{run.end_ns / 1e9:.3f} s)",
            file=sys.stderr,
        )
    return window.finish(run.problem(), run.path, "echoed")
