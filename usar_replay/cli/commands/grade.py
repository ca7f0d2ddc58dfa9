"""`usar grade`: grade recordings as recorded, one table or a line per recording."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from usar_replay.cli import options, parser_parts
from usar_replay.cli.exits import EXIT_FAIL, EXIT_INCOMPLETE, EXIT_OK, EXIT_USAGE
from usar_replay.core.errors import UsageError, UsarError
from usar_replay.core.safe_text import safe

if TYPE_CHECKING:
    from usar_replay.core.settings import Thresholds
    from usar_replay.grading.verdict import GradeReport

__all__ = ["add_parser", "run"]


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """This command's sub-parser and options (``usar COMMAND --help`` shows them)."""
    p = sub.add_parser("grade", help="grade recordings against the course rubric")
    p.add_argument("files", nargs="+", metavar="FILE|DIR")
    p.add_argument("--jobs", type=int, default=1, metavar="N", help="grade N files in parallel")
    p.add_argument(
        "--details", action="store_true", help="the full table of every recording of a batch"
    )
    parser_parts.grade_outputs(p)
    p.set_defaults(func=run)


def _grade_one(path: str, thresholds: Thresholds | None) -> GradeReport | tuple[str, int]:
    """Grade one file; a user error becomes (message, exit code) so one bad file among many is
    one line, not the end of the batch (and so it crosses a process boundary as plain data)."""
    from usar_replay.grading.grade import grade_file

    try:
        return grade_file(path, thresholds)
    except UsarError as err:
        return (str(err), err.exit_code)
    except OSError as err:  # vanished or unreadable while the batch ran
        return (f"{path}: cannot read the file: {err.strerror or err}", EXIT_USAGE)


def _ignore_sigint() -> None:
    """Grading workers leave Ctrl-C to the parent, which stops the batch with one line."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _grade_all(
    files: Sequence[str], th: Thresholds | None, jobs: int
) -> list[GradeReport | tuple[str, int]]:
    """Grade every file (``jobs`` processes), with a progress bar on a terminal."""
    if len(files) < 2:  # no bar and no pool: spare the one-file grade their imports
        return [_grade_one(f, th) for f in files]
    from concurrent.futures import Future, ProcessPoolExecutor, as_completed

    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn

    console = Console(stderr=True)
    progress = Progress(
        TextColumn("grading"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("{task.description}"),
        console=console,
        transient=True,
        disable=not console.is_terminal or len(files) < 2,
    )
    results: list[GradeReport | tuple[str, int] | None] = [None] * len(files)
    with progress:
        task = progress.add_task("", total=len(files))
        if jobs > 1 and len(files) > 1:
            import multiprocessing

            # spawn, not fork: the progress bar's refresh thread may hold a lock at fork time
            pool = ProcessPoolExecutor(
                max_workers=min(jobs, len(files)),
                initializer=_ignore_sigint,
                mp_context=multiprocessing.get_context("spawn"),
            )
            try:
                futures: dict[Future[GradeReport | tuple[str, int]], int] = {
                    pool.submit(_grade_one, f, th): i for i, f in enumerate(files)
                }
                for fut in as_completed(futures):
                    i = futures[fut]
                    results[i] = fut.result()
                    progress.update(task, advance=1, description=Path(files[i]).name)
            except KeyboardInterrupt:
                import signal

                signal.signal(signal.SIGINT, signal.SIG_IGN)  # a second Ctrl-C: still one line
                pool.shutdown(wait=True, cancel_futures=True)
                raise
            pool.shutdown()
        else:
            for i, f in enumerate(files):
                results[i] = _grade_one(f, th)
                progress.update(task, advance=1, description=Path(f).name)
    return [r for r in results if r is not None]


def run(args: argparse.Namespace) -> int:
    from usar_replay.cli.textout import incomplete_note
    from usar_replay.grading.reports import summary_line, to_table

    if args.jobs < 1:
        raise UsageError(f"--jobs {args.jobs}: expected 1 or more")
    files = options.find_recordings(args.files)
    th = options.thresholds(args)
    options.check_outputs(args, files)
    results = _grade_all(files, th, args.jobs)
    reports = [r for r in results if not isinstance(r, tuple)]
    errors = [(f, r[0]) for f, r in zip(files, results, strict=True) if isinstance(r, tuple)]
    for r in reports:
        if len(files) == 1 or args.details:
            print(to_table(r))
            print()
        if not r.log_complete:
            print(incomplete_note(r.source, r.log_problem, "graded"), file=sys.stderr)
    for _, message in errors:
        print(f"usar: error: {safe(message)}", file=sys.stderr)
    if len(files) > 1:
        print(f"Grade of {len(files)} recordings:")
        for f, res in zip(files, results, strict=True):
            if isinstance(res, tuple):
                print(summary_line(None, f, res[0].removeprefix(f"{f}: ")))
            else:
                print(summary_line(res, f))
        passed = sum(r.passed and r.log_complete for r in reports)
        print(f"{passed}/{len(files)} recordings pass")
    options.reports_out(args, reports, errors, files)
    codes = [r[1] for r in results if isinstance(r, tuple)]
    if codes:
        return max(codes)
    if any(not r.log_complete for r in reports):
        return EXIT_INCOMPLETE
    return EXIT_OK if all(r.passed for r in reports) else EXIT_FAIL
