"""`usar recover`: a readable, indexed log from a killed recording's ``.part``."""

from __future__ import annotations

import argparse

from usar_replay.cli.exits import EXIT_OK
from usar_replay.cli.textout import print_wrapped, wrap

__all__ = ["add_parser", "run"]


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """This command's sub-parser and options (``usar COMMAND --help`` shows them)."""
    p = sub.add_parser(
        "recover", help="turn a killed recording's .part (or a damaged log) into a whole log"
    )
    p.add_argument("file", metavar="FILE", help="the .part or damaged .mcap")
    p.add_argument(
        "-o",
        "--out",
        metavar="OUT",
        help="output (default: FILE without .part, else NAME.recovered.mcap)",
    )
    p.add_argument("--overwrite", action="store_true", help="replace an existing output file")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from usar_replay.log.recover import recover

    result = recover(args.file, args.out, overwrite=args.overwrite)
    of = "" if result.messages_total is None else f" of {result.messages_total}"
    print_wrapped(
        f"recovered {result.messages}{of} messages (up to sim time "
        f"{result.last_time_ns / 1e9:.3f} s), marked interrupted"
    )
    for word, path in (("from", result.source), ("into", result.output)):
        print("\n".join(wrap(f"  {word} {path}", indent="    ")))
    if result.damage:
        print_wrapped(f"what was damaged: {result.damage}")
    return EXIT_OK
