"""`usar report`: an HTML page per recording and an index."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from usar_replay.cli import options
from usar_replay.cli.exits import EXIT_INCOMPLETE, EXIT_OK, EXIT_USAGE
from usar_replay.cli.textout import incomplete_note
from usar_replay.core.errors import UsarError
from usar_replay.core.safe_text import safe

if TYPE_CHECKING:
    from usar_replay.core.settings import Thresholds
    from usar_replay.grading.verdict import GradeReport

__all__ = ["add_parser", "run"]


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """This command's sub-parser and options (``usar COMMAND --help`` shows them)."""
    p = sub.add_parser("report", help="write an HTML page per recording (map, rubric, frames)")
    p.add_argument("files", nargs="+", metavar="FILE|DIR")
    p.add_argument("-o", "--out", required=True, metavar="DIR", help="folder for the pages")
    p.add_argument(
        "--thresholds", metavar="TOML", help="override rubric thresholds ([thresholds] table)"
    )
    p.add_argument("--overwrite", action="store_true", help="replace existing pages")
    p.set_defaults(func=run)


def _report_one(
    path: str, th: Thresholds | None, page: Path, overwrite: bool
) -> GradeReport | tuple[str, int]:
    """Grade one recording and write its page; a user error becomes (message, exit code)."""
    from usar_replay.core.outfiles import write_text
    from usar_replay.grading.grade import grade_run
    from usar_replay.grading.htmlreport import collect, run_page
    from usar_replay.log.run import open_run

    try:
        run = open_run(path)
        report = grade_run(run, th)
        write_text(page, run_page(run, report, collect(run)), overwrite=overwrite, inputs=[path])
        return report
    except UsarError as err:
        return (str(err), err.exit_code)
    except OSError as err:
        return (f"{path}: cannot read the file: {err.strerror or err}", EXIT_USAGE)


def run(args: argparse.Namespace) -> int:
    from usar_replay.core.outfiles import check_output, write_text
    from usar_replay.grading.htmlreport import index_page, output_paths

    files = options.find_recordings(args.files)
    th = options.thresholds(args)
    outputs = output_paths(args.out, files)
    for p in outputs:
        check_output(p, overwrite=args.overwrite, inputs=files, option="-o")
    entries: list[tuple[str, str, GradeReport | None, str]] = []
    worst = EXIT_OK
    for f, page in zip(files, outputs, strict=False):
        result = _report_one(f, th, page, args.overwrite)
        if isinstance(result, tuple):
            print(f"usar: error: {safe(result[0])}", file=sys.stderr)
            entries.append((f, page.name, None, result[0]))
            worst = max(worst, result[1])
            continue
        entries.append((f, page.name, result, ""))
        print(f"wrote {page}")
        if not result.log_complete:
            print(incomplete_note(f, result.log_problem, "reported"), file=sys.stderr)
            worst = max(worst, EXIT_INCOMPLETE)
    write_text(outputs[-1], index_page(entries), overwrite=args.overwrite, inputs=files)
    print(f"wrote {outputs[-1]} ({len(files)} recordings)")
    _class_pages(args, files, outputs)
    return worst


def _class_pages(args: argparse.Namespace, files: list[str], outputs: list[Path]) -> None:
    """For each folder given that is a ``usar batch`` output (its ``class.json``): the class
    page, ``class.html`` (``class-2.html``, ... for more), each run linked to its page."""
    from usar_replay.batch.classpage import class_page
    from usar_replay.batch.classreport import from_folder
    from usar_replay.core.outfiles import write_text

    pages = {str(Path(f).resolve()): page.name for f, page in zip(files, outputs, strict=False)}
    n = 0
    for given in args.files:
        root = Path(given)
        grades = from_folder(root) if root.is_dir() else None
        if grades is None:
            continue
        n += 1

        def link(team: str, world: str, root: Path = root) -> str | None:
            return pages.get(str((root / team / f"{world}.mcap").resolve()))

        out = Path(args.out) / ("class.html" if n == 1 else f"class-{n}.html")
        write_text(out, class_page(grades, link), overwrite=True)
        print(f"wrote {out} (the class of {root}: {len(grades.teams)} teams)")
