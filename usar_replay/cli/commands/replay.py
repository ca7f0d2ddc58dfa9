"""`usar replay`: re-run a mission from a log, compare its outputs, grade with ``--grade``."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

from usar_replay.cli import options, parser_parts
from usar_replay.cli.exits import EXIT_FAIL, EXIT_INCOMPLETE, EXIT_MISSION, EXIT_OK
from usar_replay.cli.textout import incomplete_note
from usar_replay.core.errors import UsageError

if TYPE_CHECKING:
    from usar_replay.grading.delta import RubricDelta
    from usar_replay.grading.verdict import GradeReport
    from usar_replay.pipeline.replay import ReplayReport

__all__ = ["add_parser", "run"]


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """This command's sub-parser and options (``usar COMMAND --help`` shows them)."""
    p = sub.add_parser("replay", help="re-run the mission from a log and compare its outputs")
    p.add_argument("file", metavar="FILE")
    p.add_argument("--grade", action="store_true", help="then grade the replayed outputs")
    p.add_argument(
        "--expect-changes",
        action="store_true",
        help="report differences without failing (regression runs of changed code or settings)",
    )
    parser_parts.mission_options(p, replay=True)
    ros1 = p.add_argument_group("a ROS 1 log (docs/ros1.md)")
    ros1.add_argument(
        "--ros1", metavar="PKG", help="re-run this catkin package (default: the recorded one)"
    )
    ros1.add_argument("--launch", metavar="FILE", help="with --ros1: roslaunch this launch file")
    ros1.add_argument("--node", metavar="EXE", help="with --ros1: rosrun this executable")
    parser_parts.grade_outputs(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from usar_replay.grading.delta import rubric_delta
    from usar_replay.grading.grade import grade_run
    from usar_replay.grading.reports import to_table
    from usar_replay.grading.rubrics import rubric_for
    from usar_replay.grading.verdict import RubricGrader
    from usar_replay.log.run import open_run
    from usar_replay.pipeline.replay import check_not_damaged, replay

    options.check_outputs(args, [args.file])  # before minutes of work, not after
    run = open_run(args.file)
    target = process = None
    if not args.mission and run.mission.target.startswith("ros1:"):
        from usar_replay.ros1.replay import ros1_process

        target, process = ros1_process(
            run, args.ros1, args.launch, args.node, options.limits(args)
        )
    elif args.ros1 or args.launch or args.node:
        raise UsageError("--ros1, --launch and --node replay a ROS 1 log")
    changed = bool(args.set or args.settings)
    settings = options.run_settings(args, run.settings) if changed else None
    thresholds = options.thresholds(args)  # a bad thresholds file is a usage error before any work
    grader: RubricGrader | None = None
    rubric = rubric_for(run.require_scenario())
    # other code or settings on a log with ground truth: grade both sides and show the delta
    other_package = target is not None and target.sha256 != run.mission.sha256
    want_delta = bool(args.mission or changed or other_package) and all(
        t in run.topics for t in rubric.required_topics
    )
    if args.grade or want_delta:
        grader = rubric.grader(run.require_scenario(), thresholds)
    report = replay(
        run,
        settings,
        mission=args.mission,
        grade_sink=None if grader is None else grader.feed,
        grade_topics=rubric.grade_topics,
        required_topics=rubric.required_topics if args.grade else (),
        limits=options.limits(args),
        target=target,
        process=process,
    )
    check_not_damaged(report)
    replayed: GradeReport | None = None
    if grader is not None:
        replayed = grader.report(
            f"{args.file} (replayed)",
            log_complete=not report.log_problem,
            log_problem=report.log_problem,
        )
    delta = None
    if want_delta and replayed is not None and report.regression:
        delta = rubric_delta(grade_run(run, thresholds), replayed)
    print(
        "\n".join(
            report.lines(
                expect_changes=args.expect_changes,
                before_verdict=() if delta is None else delta.lines(),
            )
        )
    )
    code = EXIT_OK if report.identical or args.expect_changes else EXIT_FAIL
    if report.mission_failure is not None:
        code = EXIT_MISSION
    grades = []
    if args.grade and replayed is not None:
        grades.append(replayed)
        print()
        print(to_table(replayed))
        if not replayed.passed and code == EXIT_OK:
            code = EXIT_FAIL
    _replay_reports_out(args, report, grades, delta)
    if report.log_problem:
        print(incomplete_note(args.file, report.log_problem, "replayed"), file=sys.stderr)
        return EXIT_INCOMPLETE
    return code


def _replay_reports_out(
    args: argparse.Namespace,
    report: ReplayReport,
    grades: Sequence[GradeReport],
    delta: RubricDelta | None,
) -> None:
    """``usar replay --json/--junit/--csv``: the comparison (and the grade with ``--grade``)."""
    from usar_replay.core.outfiles import write_text
    from usar_replay.grading import reports as rep
    from usar_replay.pipeline import replay_report as rr

    outputs: tuple[tuple[str, str | None, Callable[[], str]], ...] = (
        ("--json", args.json, lambda: rr.replay_to_json(report, grades, delta)),
        ("--junit", args.junit, lambda: rr.replay_to_junit(report, grades)),
        ("--csv", args.csv, lambda: rep.to_csv(grades) if grades else rr.replay_to_csv(report)),
    )
    for opt, path, make in outputs:
        if path:
            write_text(
                path,
                make(),
                overwrite=args.overwrite,
                inputs=options.output_inputs(args, ()),
                option=opt,
            )
