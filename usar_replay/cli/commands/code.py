"""`usar code`: grade the code submission of packages or a class, copies and report flagged."""

from __future__ import annotations

import argparse
import sys

__all__ = ["add_parser", "run"]


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """This command's sub-parser and options (``usar COMMAND --help`` shows them)."""
    p = sub.add_parser(
        "code",
        help="grade the code submission (docs, OOP, unused code, style), find copies",
        description=(
            "Grade the code submission of each package (a team folder, a repository, a catkin "
            "workspace, or a class folder of team folders) by a rubric of measured lines "
            "(docs/code-rubric.md); list pairs of teams whose own code is similar, and the "
            "report's flags, for a person. Exit 0 when every team was graded with every tool, "
            "1 when a team's folder could not be read or a tool is missing."
        ),
    )
    p.add_argument("paths", nargs="+", metavar="PKG|DIR")
    p.add_argument("--template", metavar="DIR",
                   help="the course template's package: its code is boilerplate, never a team's")
    p.add_argument("--rubric", metavar="TOML", help="a rubric file (default: the course's)")
    p.add_argument("--json", metavar="P", help="write the grades as JSON (usar-code/1)")
    p.add_argument("--csv", metavar="P", help="write one row per team as CSV")
    p.add_argument("--html", metavar="P", help="write the similar pairs' passages side by side")
    p.add_argument("--jobs", type=int, default=1, metavar="N", help="grade N teams at a time")
    p.add_argument("--compile", action="store_true",
                   help="also build each file syntax-only for warnings (~4 s a file)")
    p.add_argument("--overwrite", action="store_true", help="replace existing output files")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from usar_replay.cli.exits import EXIT_FAIL, EXIT_OK
    from usar_replay.code import classgrade, output, rubric, template
    from usar_replay.code.compile import message_includes
    from usar_replay.code.grade import Options
    from usar_replay.code.html import pairs_html
    from usar_replay.core.errors import UsageError, UsarError
    from usar_replay.core.outfiles import check_output, write_text

    if args.jobs < 1:
        raise UsageError(f"--jobs {args.jobs}: give 1 or more")
    outs = {k: getattr(args, k) for k in ("json", "csv", "html") if getattr(args, k)}
    for opt, path in outs.items():
        check_output(path, overwrite=args.overwrite, inputs=args.paths, option=f"--{opt}")
    rub = rubric.load(args.rubric)
    tmpl = template.NO_TEMPLATE
    if args.template:
        try:
            tmpl = template.read_template(args.template)
        except UsarError as err:
            raise UsageError(f"--template {args.template}: {err}".replace("--ros1 ", "")) from None
    opts = Options(compile=args.compile, includes=tuple(message_includes()) if args.compile else ())
    done = classgrade.grade_class(args.paths, rub, tmpl, opts, jobs=args.jobs)
    print(output.to_text(done.grades, done.similar, done.threshold), end="")
    if not args.template:
        print("no --template: the course template's code counts as each team's own")
    if "json" in outs:
        doc = output.to_json(
            done.grades, done.similar, rubric=rub.name, template=args.template,
            threshold=done.threshold,
        )  # fmt: skip
        write_text(outs["json"], doc, overwrite=args.overwrite)
    if "csv" in outs:
        write_text(outs["csv"], output.to_csv(done.grades, done.similar), overwrite=args.overwrite)
    if "html" in outs:
        write_text(outs["html"], pairs_html(done.similar, done.threshold),
                   overwrite=args.overwrite)  # fmt: skip
    # a missing tool: one line each, naming the Debian package; the lines that need it say so
    needs: dict[str, set[str]] = {}
    for g in done.grades:
        for s in g.lines:
            if "is not installed" in s.note:
                needs.setdefault(s.note, set()).add(f"{s.line.id}")
        for p in g.report.problems if g.report else ():
            if "is not installed" in p:
                needs.setdefault(p, set()).add("the report's flags")
    gone = sorted(needs)
    for line in gone:
        n = len([x for x in needs[line] if x != "the report's flags"])
        what = f"{n} rubric lines not scored" if n else "report flags partial"
        print(f"usar code: {line}; {what}", file=sys.stderr)
    bad = [g.team for g in done.grades if g.verdict != "graded"]
    return EXIT_FAIL if gone or bad else EXIT_OK
