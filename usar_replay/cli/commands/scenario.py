"""`usar scenario`: print, write or check a world."""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING

from usar_replay.cli import options
from usar_replay.cli.exits import EXIT_FAIL, EXIT_OK

if TYPE_CHECKING:
    pass

__all__ = ["add_parser", "run"]


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """This command's sub-parser and options (``usar COMMAND --help`` shows them)."""
    p = sub.add_parser(
        "scenario", help="print a world as TOML (the course, a seeded variant, or a checked file)"
    )
    options.add_world_options(p)
    p.add_argument("--out", metavar="FILE", help="write the TOML here instead of stdout")
    p.add_argument("--overwrite", action="store_true", help="replace an existing output file")
    p.add_argument(
        "--check",
        action="store_true",
        help="check that the world can be completed (prints a verdict; exit 1 if it cannot)",
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from usar_replay.core.outfiles import write_text
    from usar_replay.world.scenario_toml import to_toml

    scenario = options.load_scenario(args)
    text = to_toml(scenario)
    if args.out:
        inputs = [args.scenario] if args.scenario else []
        out = write_text(args.out, text, overwrite=args.overwrite, inputs=inputs, option="--out")
        print(f"wrote {out}: {scenario.summary().splitlines()[0]}", file=sys.stderr)
    elif not args.check:
        print(text, end="")
    if not args.check:
        return EXIT_OK
    if scenario.assignment == "ros2-final":
        from usar_replay.world.ros2_world import check_ros2

        problem = check_ros2(scenario)
        if problem is not None:
            print(f"FAIL {scenario.name}: {problem}")
            return EXIT_FAIL
        print(
            f"ok   {scenario.name}: the marker is in view from aruco_target, every destination "
            "is reachable"
        )
        return EXIT_OK
    from usar_replay.world.scenario_check import check

    verdict = check(scenario)
    print("\n".join(verdict.lines()))
    return EXIT_OK if verdict.ok else EXIT_FAIL
