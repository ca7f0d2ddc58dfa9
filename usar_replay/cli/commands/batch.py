"""`usar batch`: grade a class, every team's mission on every world."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from usar_replay.cli import options, parser_parts
from usar_replay.cli.exits import EXIT_FAIL, EXIT_INTERRUPTED, EXIT_OK
from usar_replay.cli.textout import print_wrapped
from usar_replay.core.errors import UsageError, UsarError
from usar_replay.core.limits import BATCH_LIMITS

__all__ = ["add_parser", "run"]


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """This command's sub-parser and options (``usar COMMAND --help`` shows them)."""
    p = sub.add_parser(
        "batch", help="grade a class: every team's mission on every world, resumably"
    )
    p.add_argument("submissions", metavar="SUBMISSIONS_DIR", help="a .py file or folder per team")
    p.add_argument("--seeds", metavar="N-M", help="seeded variants of the course world, e.g. 0-4")
    options.add_world_key(p)
    p.add_argument(
        "--scenario", nargs="+", action="extend", metavar="FILE", help="scenario TOML worlds"
    )
    p.add_argument("-o", "--out", required=True, metavar="OUT_DIR", help="the batch's folder")
    p.add_argument("--jobs", type=int, metavar="N", help="runs at a time (default: one per core)")
    p.add_argument("--engine", choices=["local", "ray"], default="local", help="where runs run")
    p.add_argument("--address", metavar="ADDR", help="Ray cluster address (--engine ray)")
    parser_parts.class_run_options(p)
    parser_parts.limit_options(p, "batch", BATCH_LIMITS)
    parser_parts.class_grade_options(p)
    p.add_argument("--gradescope", action="store_true", help="write TEAM/results.json per team")
    p.add_argument(
        "--starts",
        metavar="TOML",
        help="the instructor's starts: a table per team (launch, node, after_launch, note)",
    )
    p.add_argument("--quiet", action="store_true", help="no progress bar or per-run lines")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """``usar batch``: every team's mission on every world, recorded, graded, summarised."""
    import dataclasses as dc
    import os

    from usar_replay.batch.driver import grade_class, plan_class
    from usar_replay.batch.engines import make_engine
    from usar_replay.batch.plan import parse_seeds
    from usar_replay.core.settings import RunSettings
    from usar_replay.core.settings import to_toml as settings_to_toml

    jobs = args.jobs if args.jobs is not None else (os.cpu_count() or 1)
    if jobs < 1:
        raise UsageError(f"--jobs {jobs}: expected 1 or more")
    limits = options.run_limits(args)  # before any other work: a bad limit is one line
    base = RunSettings()
    if args.max_sim_time is not None:
        base = dc.replace(base, record=dc.replace(base.record, max_sim_time_s=args.max_sim_time))
    settings = options.run_settings(args, base)
    thresholds = ""
    if args.thresholds:
        options.thresholds(args)  # a bad file is a usage error before any run
        thresholds = Path(args.thresholds).read_text(encoding="utf-8")
    if args.code_template and not args.code:
        raise UsageError("--code-template: give --code too (it is the code grade's template)")
    if args.code_template:
        from usar_replay.code.template import read_template

        try:
            read_template(args.code_template)  # a bad template is a usage error before any run
        except UsarError as err:
            raise UsageError(f"--code-template {args.code_template}: {err}") from None
    starts = None
    if args.starts:
        from usar_replay.ros1.starts_file import read_starts

        starts = read_starts(args.starts)  # a mistake is a usage error before any run
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise UsageError(f"-o {out}: is a file; give a folder for the batch's output")
    plan = plan_class(
        args.submissions,
        out,
        seeds=parse_seeds(args.seeds) if args.seeds else (),
        scenarios=args.scenario or (),
        settings_toml=settings_to_toml(settings),
        thresholds_toml=thresholds,
        limits=limits,
        sandbox=not args.no_sandbox,
        world_key=options.world_key(args),
        starts=starts,
    )
    if plan.jobs and not args.no_sandbox:
        from usar_replay.batch.machine import warning

        said = warning()
        if said:  # where isolation is partial: what it means, once (`usar doctor` says more)
            print_wrapped(said, file=sys.stderr)
    engine = make_engine(args.engine, jobs, args.address) if plan.jobs else None
    slots = getattr(engine, "slots", jobs)
    if slots < jobs and not args.quiet:
        print(f"usar: {slots} runs at a time: {slots} CPUs are free (one CPU set per run)",
              file=sys.stderr)  # fmt: skip
    try:
        summary = grade_class(
            plan,
            engine or make_engine("local", 1),
            gradescope=args.gradescope,
            visibility=args.visibility,
            quiet=args.quiet,
            code=args.code,
            code_template=args.code_template,
            code_jobs=jobs,
        )
    except KeyboardInterrupt:
        print(
            "usar: interrupted; finished runs are kept, the cut-off ones are redone when the "
            "same command runs again",
            file=sys.stderr,
        )
        return EXIT_INTERRUPTED
    print(summary.table)
    print()
    print("\n".join(summary.lines()))
    print_wrapped(f"wrote {plan.out_root}/summary.csv, summary.txt and a folder per team")
    if summary.interrupted:
        return EXIT_INTERRUPTED
    return EXIT_FAIL if summary.errors else EXIT_OK
