"""`usar view`: a recording's timeline in the rerun viewer."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from usar_replay.cli import parser_parts
from usar_replay.cli.exits import EXIT_INCOMPLETE, EXIT_OK
from usar_replay.core.safe_text import safe_line

if TYPE_CHECKING:
    pass

__all__ = ["add_parser", "run"]


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """This command's sub-parser and options (``usar COMMAND --help`` shows them)."""
    p = sub.add_parser("view", help="show a recording's timeline in the rerun viewer")
    p.add_argument("file", metavar="FILE")
    p.add_argument(
        "--save", metavar="OUT.rrd", help="write an .rrd (default without a display: FILE.rrd)"
    )
    p.add_argument("--web", action="store_true", help="serve the web viewer until Ctrl-C")
    p.add_argument("--grade", action="store_true", help="add the rubric lines to the log view")
    p.add_argument(
        "--web-port", type=parser_parts.port, default=9090, metavar="N", help="web viewer port"
    )
    p.add_argument(
        "--grpc-port",
        type=parser_parts.port,
        default=9876,
        metavar="N",
        help="viewer data (gRPC) port",
    )
    p.add_argument(
        "--bind",
        type=parser_parts.address,
        default="127.0.0.1",
        metavar="ADDR",
        help="address both viewer ports listen on (0.0.0.0: every interface; default 127.0.0.1)",
    )
    p.add_argument("--overwrite", action="store_true", help="replace an existing .rrd")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import os

    # rerun's own log lines (a failed file write is two ERROR lines from its writer thread) would
    # break the one-line error contract; the failure itself still raises and is reported below
    os.environ.setdefault("RUST_LOG", "off")
    from usar_replay.log.run import open_run
    from usar_replay.viewer.view import view_run, wait_until_interrupted
    from usar_replay.viewer.viewer_process import check_rrd, choose_output, open_command

    output = choose_output(args.file, save=args.save, web=args.web, env=os.environ)
    if output.rrd is not None:  # before any work: never over the log or an existing file
        check_rrd(output.rrd, Path(args.file), overwrite=args.overwrite, option="--save")
    run = open_run(args.file)
    result = view_run(
        run,
        output,
        grade=args.grade,
        overwrite=args.overwrite,
        grpc_port=args.grpc_port,
        web_port=args.web_port,
        bind=args.bind,
    )
    if result.viewer_problem:
        print(f"usar: {result.viewer_problem}; wrote the view to a file", file=sys.stderr)
    if result.rrd is not None:
        print(
            f"wrote {result.rrd} ({result.frames} camera frames, {result.messages} messages, "
            f"{result.seconds:.1f} s); open it with:"
        )
        print(open_command(result.rrd))
    if result.spawned:
        print(f"sent {args.file} to the rerun viewer ({result.frames} camera frames)")
    problems = [f"the log is incomplete ({result.problem})"] if result.problem else []
    problems += [result.grade_problem] if result.grade_problem else []
    if problems:
        text = safe_line("; ".join(problems))  # a damage's words may quote the log's names
        print(f"usar: {args.file}: {text}; the view shows what was read", file=sys.stderr)
    if result.url:
        print(f"serving the web viewer at {result.url} (Ctrl-C to stop)", flush=True)
        wait_until_interrupted(result)
    return EXIT_INCOMPLETE if problems else EXIT_OK
