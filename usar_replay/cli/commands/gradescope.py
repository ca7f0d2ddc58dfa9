"""`usar gradescope`: grade the one submission of a Gradescope autograder, in place."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from usar_replay.cli import options, parser_parts
from usar_replay.cli.exits import EXIT_FAIL, EXIT_INTERRUPTED, EXIT_OK
from usar_replay.cli.textout import print_wrapped
from usar_replay.core.errors import UsageError, UsarError
from usar_replay.core.limits import GRADESCOPE_LIMITS

if TYPE_CHECKING:
    from usar_replay.batch.gradescope import Autograder

__all__ = ["add_parser", "run"]


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """This command's sub-parser and options (``usar COMMAND --help`` shows them)."""
    p = sub.add_parser(
        "gradescope",
        help="a Gradescope autograder: grade /autograder/submission in place into "
        "/autograder/results/results.json (docs/gradescope.md)",
    )
    p.add_argument(
        "--submission",
        metavar="DIR",
        help="the submission's folder (default: $USAR_AUTOGRADER/submission, /autograder/...)",
    )
    p.add_argument(
        "--results",
        metavar="FILE",
        help="the results file (default: $USAR_AUTOGRADER/results/results.json)",
    )
    p.add_argument(
        "--work", metavar="DIR", help="the runs' files (default: a new folder in $TMPDIR)"
    )
    p.add_argument("--seeds", metavar="N-M", help="seeded variants of the course world, e.g. 0")
    options.add_world_key(p)
    p.add_argument(
        "--scenario", nargs="+", action="extend", metavar="FILE", help="scenario TOML worlds"
    )
    parser_parts.class_run_options(p)
    parser_parts.limit_options(p, "gradescope", GRADESCOPE_LIMITS)
    parser_parts.class_grade_options(p)
    p.add_argument("--quiet", action="store_true", help="no per-run lines")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """``usar gradescope``: the results file first (0 points, "grading started"), then after
    each world, then whole; a usage error is in it too (0 points and the line)."""
    from usar_replay.batch.gradescope import Autograder, error_results, write_results

    where = Autograder.here(args.submission, args.results)
    try:
        return _grade(args, where)
    except (UsageError, UsarError) as err:  # the instructor's setup: said in the results too
        write_results(where.results, error_results(str(err)))
        raise


def _grade(args: argparse.Namespace, where: Autograder) -> int:
    import dataclasses as dc
    import tempfile

    from usar_replay.batch.gradescope import grade_submission
    from usar_replay.batch.plan import make_worlds, parse_seeds
    from usar_replay.core.settings import RunSettings
    from usar_replay.core.settings import to_toml as settings_to_toml

    limits = options.run_limits(args)
    if args.code_template and not args.code:
        raise UsageError("--code-template: give --code too (it is the code grade's template)")
    base = RunSettings()
    if args.max_sim_time is not None:
        base = dc.replace(base, record=dc.replace(base.record, max_sim_time_s=args.max_sim_time))
    settings = options.run_settings(args, base)
    thresholds = ""
    if args.thresholds:
        options.thresholds(args)  # a bad file is a usage error before any run
        thresholds = Path(args.thresholds).read_text(encoding="utf-8")
    if not where.submission.is_dir():
        raise UsageError(
            f"{where.submission}: no submission folder here; give --submission DIR (or set "
            "USAR_AUTOGRADER to the autograder's root)"
        )
    seeds = parse_seeds(args.seeds) if args.seeds else ()
    worlds = make_worlds(seeds, args.scenario or (), options.world_key(args))
    work = Path(args.work) if args.work else Path(tempfile.mkdtemp(prefix="usar-gradescope-"))
    try:
        final, summary = grade_submission(
            where,
            worlds,
            work,
            settings_toml=settings_to_toml(settings),
            thresholds_toml=thresholds,
            limits=limits,
            sandbox=not args.no_sandbox,
            visibility=args.visibility,
            quiet=args.quiet,
            code=args.code,
            code_template=args.code_template,
        )
    except KeyboardInterrupt:
        print("usar: interrupted; the results file has the worlds graded so far", file=sys.stderr)
        return EXIT_INTERRUPTED
    print(summary.table)
    print()
    print_wrapped(f"{final['score']:g}/{final.get('max_score', 0):g} points; wrote {where.results}")
    return EXIT_FAIL if summary.errors else EXIT_OK
