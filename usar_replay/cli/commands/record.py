"""`usar record`: run a mission live and record it; a status line while it runs."""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from usar_replay.cli import options, parser_parts
from usar_replay.cli.exits import EXIT_FAIL, EXIT_MISSION, EXIT_OK
from usar_replay.cli.status_display import StatusDisplay
from usar_replay.cli.textout import print_wrapped
from usar_replay.core.errors import UsageError

if TYPE_CHECKING:
    from collections.abc import Callable

    from usar_replay.core.settings import RunSettings
    from usar_replay.pipeline.record import Progress, RecordResult
    from usar_replay.process.mission_process import MissionLimits
    from usar_replay.world.scenario import Scenario

__all__ = ["add_parser", "run"]


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """This command's sub-parser and options (``usar COMMAND --help`` shows them)."""
    p = sub.add_parser("record", help="run the mission in pybullet and record it to MCAP")
    options.add_world_options(p)
    p.add_argument("--out", metavar="PATH", help="output .mcap (default: recordings/NAME.mcap)")
    p.add_argument(
        "--renderer", choices=["auto", "tiny", "egl"], default="auto", help="pybullet renderer"
    )
    p.add_argument(
        "--max-sim-time",
        type=parser_parts.positive_seconds,
        metavar="S",
        help="hard stop in sim seconds (>0)",
    )
    p.add_argument("--quiet", action="store_true", help="no progress line")
    parser_parts.mission_options(p, replay=False)
    p.add_argument("--overwrite", action="store_true", help="replace an existing output file")
    ros1 = p.add_argument_group("a ROS 1 catkin package as the mission (docs/ros1.md)")
    ros1.add_argument("--ros1", metavar="PKG", help="catkin package folder: build it and run it")
    ros1.add_argument("--launch", metavar="FILE", help="with --ros1: roslaunch this launch file")
    ros1.add_argument("--node", metavar="EXE", help="with --ros1: rosrun this executable")
    ros1.add_argument(
        "--after-launch",
        action="append",
        default=[],
        metavar="CMD",
        help="with --ros1: run CMD once the graph is up, as a TA types it in a third terminal "
        "('rosservice call /start \"data: true\"'); repeatable. Without --launch/--node the "
        "package starts as its doc/instructions.txt, README or usar.toml says",
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from usar_replay.core.settings import RunSettings
    from usar_replay.pipeline.record import default_output, print_summary, record

    scenario = options.load_scenario(args)
    out = Path(args.out) if args.out else default_output(scenario)
    if out.exists() and not args.overwrite:
        raise UsageError(f"{out} exists; pass --overwrite to replace it, or --out another path")
    base = RunSettings()
    base = dataclasses.replace(
        base,
        record=dataclasses.replace(
            base.record, renderer=args.renderer, max_sim_time_s=args.max_sim_time
        ),
    )
    settings = options.run_settings(args, base)
    status = StatusDisplay()
    before = options.identity(out)
    try:
        progress = None if args.quiet else status
        if args.ros1:
            result = _record_ros1(args, scenario, out, settings, progress)
        else:
            if args.launch or args.node or args.after_launch:
                raise UsageError("--launch, --node and --after-launch go with --ros1 PKG")
            result = record(
                scenario,
                out,
                settings,
                progress=progress,
                mission=args.mission,
                limits=_limits(args, out),
            )
    except KeyboardInterrupt as err:
        from usar_replay.core.signals import exit_code

        status.close()
        if options.identity(out) not in (None, before):
            print(f"usar: {err}; {out} is closed and readable, marked interrupted", file=sys.stderr)
        else:
            print(f"usar: {err} before anything was recorded; no log was written", file=sys.stderr)
        return exit_code(err)
    status.close()
    print_summary(result)
    if result.outcome in ("crashed", "hung", "out_of_memory", "refused", "build_failed"):
        return EXIT_MISSION
    if not result.mission_done:
        print_wrapped(f"usar: exit 1: {_why_not_done(result, args)}", file=sys.stderr)
        return EXIT_FAIL
    return EXIT_OK


def _why_not_done(result: RecordResult, args: argparse.Namespace) -> str:
    """The one line that says why a recording that ended without a fault exits 1: the run
    stopped before the mission said it was done, so the log is not a finished run."""
    if result.outcome == "max_sim_time":
        return (
            f"stopped by --max-sim-time {args.max_sim_time:g} s before the mission said it was done"
        )
    if result.outcome == "time_limit":
        from usar_replay.pipeline.record import TIME_LIMIT_GRACE_S

        return (
            f"stopped at the world's time limit (its time_limit_s and {TIME_LIMIT_GRACE_S:g} s "
            "of grace) before the mission said it was done"
        )
    return f"the mission did not say it was done ({result.outcome})"


def _record_ros1(
    args: argparse.Namespace,
    scenario: Scenario,
    out: Path,
    settings: RunSettings,
    progress: Callable[[Progress], None] | None,
) -> RecordResult:
    """``--ros1 PKG``: build the catkin package and record it with the ROS 1 bridge."""
    from usar_replay.ros1.process import Ros1Options
    from usar_replay.ros1.record import record_ros1

    if args.mission:
        raise UsageError("--ros1 and --mission: give one mission")
    opts = Ros1Options(
        launch=args.launch or "",
        node=args.node or "",
        after_launch=tuple(args.after_launch),
        given_settings=options.given_settings(args),
    )
    return record_ros1(
        scenario, out, args.ros1, settings, progress, options=opts, limits=_limits(args, out)
    )


def _limits(args: argparse.Namespace, out: Path) -> MissionLimits:
    """The mission's limits, with the output hidden from it even at its default path."""
    limits = options.limits(args)
    return dataclasses.replace(limits, hidden=(*limits.hidden, str(out)))
