"""The `usar` command: arguments, messages to people, exit codes.

Exit codes (the same for every subcommand):

* 0 - done; for grading: every required rubric line passed.
* 1 - a rubric line or the replay comparison failed.
* 2 - usage error: bad option, bad scenario file, a command not built yet.
* 3 - the log is incomplete or corrupt (what could be read was still used, and said so).
* 4 - the mission's code crashed, hung, ran out of memory or published what it may not (the
  log is closed and records the verdict; the user's traceback is shown).
* 130, 143, 129 - interrupted by SIGINT (Ctrl-C), SIGTERM, SIGHUP (128 + the signal); a
  recording is still closed, indexed and marked interrupted.

User errors (:class:`usar_replay.core.errors.UsarError`) are printed as one line, ``usar: error:
...``, without a traceback; anything else is a bug and raises.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, NoReturn

from usar_replay import __version__
from usar_replay.core.errors import UsageError, UsarError

if TYPE_CHECKING:
    from usar_replay.core.settings import RunSettings, Thresholds
    from usar_replay.grading.grade import GradeReport
    from usar_replay.node.worker import MissionLimits
    from usar_replay.pipeline.record import Progress
    from usar_replay.pipeline.replay import ReplayReport
    from usar_replay.world.scenario import Scenario

__all__ = ["main"]

EXIT_OK = 0
EXIT_FAIL = 1
EXIT_USAGE = 2
EXIT_INCOMPLETE = 3
EXIT_MISSION = 4
EXIT_INTERRUPTED = 130


def _cmd_info(args: argparse.Namespace) -> int:
    from usar_replay.log.info import describe, is_whole, open_checked

    worst = EXIT_OK
    for i, path in enumerate(args.files):
        try:
            run = open_checked(path, quick=args.quick)
        except UsarError as err:  # one bad path among several is one line, not the end
            print(f"usar: error: {err}", file=sys.stderr)
            worst = max(worst, err.exit_code)
            continue
        if i:
            print()
        print(describe(run, quick=args.quick))
        if not is_whole(run):
            worst = max(worst, EXIT_INCOMPLETE)
    return worst


def _cmd_recover(args: argparse.Namespace) -> int:
    from usar_replay.log.recover import recover

    result = recover(args.file, args.out, overwrite=args.overwrite)
    print(result.describe())
    if result.damage:
        print(f"what was damaged: {result.damage}")
    return EXIT_OK


def _parse_camera(text: str) -> tuple[int, int, float]:
    """``640x480@10`` -> (640, 480, 10.0)."""
    import re

    m = re.fullmatch(r"(\d+)x(\d+)(?:@(\d+(?:\.\d+)?))?", text.strip())
    if not m:
        raise UsageError(f"--camera {text!r}: expected WIDTHxHEIGHT[@RATE], e.g. 640x480@10")
    w, h, rate = int(m.group(1)), int(m.group(2)), float(m.group(3) or 10)
    if not (16 <= w <= 4096 and 16 <= h <= 4096 and 0 < rate <= 60):
        raise UsageError(f"--camera {text!r}: size 16..4096 pixels and rate 0..60 Hz")
    return w, h, rate


def _load_scenario(args: argparse.Namespace) -> Scenario:
    from usar_replay.grading import assignment
    from usar_replay.world import scenario as scn

    kind = getattr(args, "assignment", None)
    base = scn.load(args.scenario) if args.scenario else assignment.by_name(kind or "usar").world()
    if kind and base.assignment != kind:
        raise UsageError(
            f"{args.scenario} is a {base.assignment!r} world, not {kind!r}; drop --assignment"
        )
    if args.seed is not None:
        base = assignment.of(base).variant(base, args.seed)
    if args.camera:
        w, h, rate = _parse_camera(args.camera)
        base = dataclasses.replace(
            base, camera=dataclasses.replace(base.camera, width=w, height=h, rate_hz=rate)
        )
    if args.encoding:
        base = dataclasses.replace(
            base, camera=dataclasses.replace(base.camera, encoding=args.encoding)
        )
    return base


def _cmd_scenario(args: argparse.Namespace) -> int:
    from usar_replay.core.outfiles import write_text
    from usar_replay.world.scenario import to_toml

    scenario = _load_scenario(args)
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


class _StatusLine:
    """One self-rewriting progress line on stderr (a plain line every 30 sim-s when not a tty)."""

    def __init__(self) -> None:
        import shutil

        self.tty = sys.stderr.isatty()
        self.width = min(shutil.get_terminal_size((100, 24)).columns, 100) - 1
        self.last_print = -1e9

    def __call__(self, p: Progress) -> None:
        text = (
            f"sim {p.sim_time_s:7.1f} s | markers {p.markers_found}/{p.markers_total} | "
            f"frames {p.frames} | {p.last_log}"
        )[: self.width]
        if self.tty:
            if p.sim_time_s - self.last_print >= 0.5:
                print("\r" + text.ljust(self.width), end="", file=sys.stderr, flush=True)
                self.last_print = p.sim_time_s
        elif p.sim_time_s - self.last_print >= 30.0:
            print(text, file=sys.stderr, flush=True)
            self.last_print = p.sim_time_s

    def close(self) -> None:
        if self.tty:
            print(file=sys.stderr)


def _overrides(items: Sequence[str] | None) -> dict[str, str]:
    overrides: dict[str, str] = {}
    for item in items or []:
        k, eq, v = item.partition("=")
        if not eq or not k.strip():
            raise UsageError(
                f"--set {item!r}: expected NAME=VALUE, e.g. detector.dictionary=DICT_5X5_50"
            )
        overrides[k.strip()] = v.strip()
    return overrides


def _run_settings(args: argparse.Namespace, base: RunSettings) -> RunSettings:
    """``--settings FILE`` then ``--set NAME=VALUE`` on top of ``base`` (one codec for all)."""
    from usar_replay.core import settings as settings_mod

    out = base
    if getattr(args, "settings", None):
        data = settings_mod.load(settings_mod.RunSettings, args.settings)
        # only the tables the file has replace the base's
        import tomllib

        given = tomllib.loads(Path(args.settings).read_text(encoding="utf-8"))
        out = dataclasses.replace(
            out, **{k: getattr(data, k) for k in ("record", "mission", "detector") if k in given}
        )
    return settings_mod.apply_overrides(out, _overrides(args.set), default_group="mission")


def _limits(args: argparse.Namespace) -> MissionLimits:
    from usar_replay.node.worker import MissionLimits

    if not (args.tick_timeout > 0):
        raise UsageError(f"--tick-timeout {args.tick_timeout}: expected a positive number of s")
    if args.mission_memory < 0:
        raise UsageError(f"--mission-memory {args.mission_memory}: expected MiB >= 0 (0: none)")
    return MissionLimits(tick_timeout_s=args.tick_timeout, memory_mb=args.mission_memory)


def _cmd_record(args: argparse.Namespace) -> int:
    from usar_replay.core.settings import RunSettings
    from usar_replay.pipeline.record import default_output, print_summary, record

    scenario = _load_scenario(args)
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
    settings = _run_settings(args, base)
    status = _StatusLine()
    before = _identity(out)
    try:
        result = record(
            scenario,
            out,
            settings,
            progress=None if args.quiet else status,
            mission=args.mission,
            limits=_limits(args),
        )
    except KeyboardInterrupt as err:
        from usar_replay.core.signals import exit_code

        status.close()
        if _identity(out) not in (None, before):
            print(f"usar: {err}; {out} is closed and readable, marked interrupted", file=sys.stderr)
        else:
            print(f"usar: {err} before anything was recorded; no log was written", file=sys.stderr)
        return exit_code(err)
    status.close()
    print_summary(result)
    if result.outcome in ("crashed", "hung", "out_of_memory", "refused"):
        return EXIT_MISSION
    return EXIT_OK if result.mission_done else EXIT_FAIL


_OUTPUT_OPTIONS = (("--json", "json"), ("--junit", "junit"), ("--csv", "csv"))


def _output_inputs(args: argparse.Namespace, inputs: Sequence[str]) -> list[str]:
    """The files a grade output may never replace: the recordings read (and a replayed one)."""
    return [*inputs, *([args.file] if getattr(args, "file", None) else [])]


def _check_outputs(args: argparse.Namespace, inputs: Sequence[str]) -> None:
    """Refuse bad outputs before any work: an input, a directory, an existing file without
    ``--overwrite``, or one path given to two options."""
    from usar_replay.core.outfiles import check_output

    seen: dict[Path, str] = {}
    for opt, name in _OUTPUT_OPTIONS:
        path = getattr(args, name, None)
        if not path:
            continue
        p = check_output(
            path, overwrite=args.overwrite, inputs=_output_inputs(args, inputs), option=opt
        )
        key = p.resolve()
        if key in seen:
            raise UsageError(f"{opt} {p}: also given to {seen[key]}; choose another path")
        seen[key] = opt


def _identity(p: Path) -> tuple[int, int] | None:
    try:
        st = p.stat()
    except OSError:
        return None
    return (st.st_ino, st.st_mtime_ns)


def _reports_out(
    args: argparse.Namespace,
    reports: Sequence[GradeReport],
    errors: Sequence[tuple[str, str]] = (),
    inputs: Sequence[str] = (),
) -> None:
    """Write the machine-readable reports asked for, each atomically; a recording that could
    not be graded at all is in them too (``errors``: (path, message)), so a CI run never loses
    one silently."""
    from usar_replay.core.outfiles import write_text
    from usar_replay.grading import reports as rep

    for opt, path, fmt in (
        ("--json", args.json, rep.to_json),
        ("--junit", args.junit, rep.to_junit),
        ("--csv", args.csv, rep.to_csv),
    ):
        if path:
            write_text(
                path,
                fmt(reports, errors),
                overwrite=args.overwrite,
                inputs=_output_inputs(args, inputs),
                option=opt,
            )


def _thresholds(args: argparse.Namespace) -> Thresholds | None:
    from usar_replay.grading.grade import load_thresholds

    return load_thresholds(args.thresholds) if args.thresholds else None


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


def _find_recordings(names: Sequence[str]) -> list[str]:
    """Files as given; a folder is searched with its sub-folders for ``*.mcap`` (sorted; hidden
    files and folders and unfinished ``.part`` files are skipped)."""
    files: list[str] = []
    for name in names:
        p = Path(name)
        if p.is_dir():
            found = sorted(
                str(f)
                for f in p.rglob("*.mcap")
                if f.is_file() and not any(s.startswith(".") for s in f.relative_to(p).parts)
            )
            if not found:
                raise UsageError(f"{p}: no .mcap files in this folder or its sub-folders")
            files += found
        else:
            files.append(name)
    return files


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


def _cmd_grade(args: argparse.Namespace) -> int:
    from usar_replay.grading.reports import summary_line, to_table

    if args.jobs < 1:
        raise UsageError(f"--jobs {args.jobs}: expected 1 or more")
    files = _find_recordings(args.files)
    th = _thresholds(args)
    _check_outputs(args, files)
    results = _grade_all(files, th, args.jobs)
    reports = [r for r in results if not isinstance(r, tuple)]
    errors = [(f, r[0]) for f, r in zip(files, results, strict=True) if isinstance(r, tuple)]
    for r in reports:
        if len(files) == 1 or args.details:
            print(to_table(r))
            print()
        if not r.log_complete:
            print(
                f"usar: {r.source}: the log is incomplete ({r.log_problem}); "
                "graded as far as it goes",
                file=sys.stderr,
            )
    for _, message in errors:
        print(f"usar: error: {message}", file=sys.stderr)
    if len(files) > 1:
        print(f"Grade of {len(files)} recordings:")
        for f, res in zip(files, results, strict=True):
            if isinstance(res, tuple):
                print(summary_line(None, f, res[0].removeprefix(f"{f}: ")))
            else:
                print(summary_line(res, f))
        passed = sum(r.passed and r.log_complete for r in reports)
        print(f"{passed}/{len(files)} recordings pass")
    _reports_out(args, reports, errors, files)
    codes = [r[1] for r in results if isinstance(r, tuple)]
    if codes:
        return max(codes)
    if any(not r.log_complete for r in reports):
        return EXIT_INCOMPLETE
    return EXIT_OK if all(r.passed for r in reports) else EXIT_FAIL


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


def _cmd_report(args: argparse.Namespace) -> int:
    from usar_replay.core.outfiles import check_output, write_text
    from usar_replay.grading.htmlreport import index_page, output_paths

    files = _find_recordings(args.files)
    th = _thresholds(args)
    outputs = output_paths(args.out, files)
    for p in outputs:
        check_output(p, overwrite=args.overwrite, inputs=files, option="-o")
    entries: list[tuple[str, str, GradeReport | None, str]] = []
    worst = EXIT_OK
    for f, page in zip(files, outputs, strict=False):
        result = _report_one(f, th, page, args.overwrite)
        if isinstance(result, tuple):
            print(f"usar: error: {result[0]}", file=sys.stderr)
            entries.append((f, page.name, None, result[0]))
            worst = max(worst, result[1])
            continue
        entries.append((f, page.name, result, ""))
        print(f"wrote {page}")
        if not result.log_complete:
            print(f"usar: {f}: the log is incomplete ({result.log_problem})", file=sys.stderr)
            worst = max(worst, EXIT_INCOMPLETE)
    write_text(outputs[-1], index_page(entries), overwrite=args.overwrite, inputs=files)
    print(f"wrote {outputs[-1]} ({len(files)} recordings)")
    return worst


def _cmd_replay(args: argparse.Namespace) -> int:
    from usar_replay.grading.grade import rubric_for
    from usar_replay.grading.reports import to_table
    from usar_replay.grading.verdict import RubricGrader
    from usar_replay.log.run import open_run
    from usar_replay.pipeline.replay import check_not_damaged, replay

    _check_outputs(args, [args.file])  # before minutes of work, not after
    run = open_run(args.file)
    changed = bool(args.set or args.settings)
    settings = _run_settings(args, run.settings) if changed else None
    thresholds = _thresholds(args)  # a bad thresholds file is a usage error before any work
    grader: RubricGrader | None = None
    rubric = rubric_for(run.require_scenario())
    if args.grade:
        grader = rubric.grader(run.require_scenario(), thresholds)
    report = replay(
        run,
        settings,
        mission=args.mission,
        grade_sink=None if grader is None else grader.feed,
        grade_topics=rubric.grade_topics,
        required_topics=rubric.required_topics if grader is not None else (),
        limits=_limits(args),
    )
    check_not_damaged(report)
    print("\n".join(report.lines()))
    code = EXIT_OK if report.identical or args.expect_changes else EXIT_FAIL
    if report.mission_failure is not None:
        code = EXIT_MISSION
    grades = []
    if grader is not None:
        g = grader.report(
            f"{args.file} (replayed)",
            log_complete=not report.log_problem,
            log_problem=report.log_problem,
        )
        grades.append(g)
        print()
        print(to_table(g))
        if not g.passed and code == EXIT_OK:
            code = EXIT_FAIL
    _replay_reports_out(args, report, grades)
    if report.log_problem:
        print(
            f"usar: {args.file}: the log is incomplete ({report.log_problem}); "
            "replayed as far as it goes",
            file=sys.stderr,
        )
        return EXIT_INCOMPLETE
    return code


def _replay_reports_out(
    args: argparse.Namespace, report: ReplayReport, grades: Sequence[GradeReport]
) -> None:
    """``usar replay --json/--junit/--csv``: the comparison (and the grade with ``--grade``)."""
    from usar_replay.core.outfiles import write_text
    from usar_replay.grading import reports as rep
    from usar_replay.pipeline import replay_report as rr

    outputs: tuple[tuple[str, str | None, Callable[[], str]], ...] = (
        ("--json", args.json, lambda: rr.replay_to_json(report, grades)),
        ("--junit", args.junit, lambda: rr.replay_to_junit(report, grades)),
        ("--csv", args.csv, lambda: rep.to_csv(grades) if grades else rr.replay_to_csv(report)),
    )
    for opt, path, make in outputs:
        if path:
            write_text(
                path,
                make(),
                overwrite=args.overwrite,
                inputs=_output_inputs(args, ()),
                option=opt,
            )


def _cmd_batch(args: argparse.Namespace) -> int:
    """``usar batch``: every team's mission on every world, recorded, graded, summarised."""
    import dataclasses as dc
    import os

    from usar_replay.batch.driver import grade_class, plan_class
    from usar_replay.batch.engines import make_engine
    from usar_replay.batch.plan import Limits, parse_seeds
    from usar_replay.core.settings import RunSettings
    from usar_replay.core.settings import to_toml as settings_to_toml

    jobs = args.jobs if args.jobs is not None else (os.cpu_count() or 1)
    if jobs < 1:
        raise UsageError(f"--jobs {jobs}: expected 1 or more")
    for opt, value in (("--tick-timeout", args.tick_timeout), ("--wall-limit", args.wall_limit)):
        if not value > 0:
            raise UsageError(f"{opt} {value}: expected a positive number of seconds")
    if args.mission_memory < 0 or args.cpu_limit < 0:
        raise UsageError("--mission-memory and --cpu-limit: expected 0 (none) or more")
    base = RunSettings()
    if args.max_sim_time is not None:
        base = dc.replace(base, record=dc.replace(base.record, max_sim_time_s=args.max_sim_time))
    settings = _run_settings(args, base)
    thresholds = ""
    if args.thresholds:
        _thresholds(args)  # a bad file is a usage error before any run
        thresholds = Path(args.thresholds).read_text(encoding="utf-8")
    limits = Limits(
        tick_timeout_s=args.tick_timeout,
        memory_mb=args.mission_memory,
        cpu_s=args.cpu_limit,
        wall_s=args.wall_limit,
        sandbox=not args.no_sandbox,
    )
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
    )
    engine = make_engine(args.engine, jobs, args.address) if plan.jobs else None
    try:
        summary = grade_class(
            plan,
            engine or make_engine("local", 1),
            gradescope=args.gradescope,
            visibility=args.visibility,
            quiet=args.quiet,
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
    print(f"wrote {plan.out_root}/summary.csv, summary.txt and a folder per team")
    if summary.interrupted:
        return EXIT_INTERRUPTED
    return EXIT_FAIL if summary.errors else EXIT_OK


def _mission_options(p: argparse.ArgumentParser, *, replay: bool) -> None:
    p.add_argument(
        "--mission",
        metavar="TARGET",
        help=(
            "mission code: a .py file or module:function that creates the nodes "
            + ("(default: the one the log recorded)" if replay else "(default: builtin)")
        ),
    )
    p.add_argument(
        "--set",
        action="append",
        metavar="NAME=VALUE",
        help="a setting, e.g. detector.dictionary=DICT_5X5_50 or mission.settle_frames=3",
    )
    p.add_argument("--settings", metavar="TOML", help="settings from [record]/[mission]/[detector]")
    p.add_argument(
        "--tick-timeout",
        type=float,
        default=10.0,
        metavar="S",
        help="wall seconds a tick's callbacks may take before the mission is 'hung' (10)",
    )
    p.add_argument(
        "--mission-memory",
        type=int,
        default=4096,
        metavar="MIB",
        help="memory limit of the mission process in MiB (4096; 0: none)",
    )


def _cmd_view(args: argparse.Namespace) -> int:
    import os

    # rerun's own log lines (a failed file write is two ERROR lines from its writer thread) would
    # break the one-line error contract; the failure itself still raises and is reported below
    os.environ.setdefault("RUST_LOG", "off")
    from usar_replay.log.run import open_run
    from usar_replay.viewer.view import (
        check_rrd,
        choose_output,
        open_command,
        view_run,
        wait_until_interrupted,
    )

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
        text = "; ".join(problems)
        print(f"usar: {args.file}: {text}; the view shows what was read", file=sys.stderr)
    if result.url:
        print(f"serving the web viewer at {result.url} (Ctrl-C to stop)", flush=True)
        wait_until_interrupted(result)
    return EXIT_INCOMPLETE if problems else EXIT_OK


def _address(text: str) -> str:
    """An IP address for the parser (what ``rerun --bind`` takes)."""
    import ipaddress

    try:
        return str(ipaddress.ip_address(text))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an IP address") from None


def _port(text: str) -> int:
    """A TCP port number for the parser (1-65535)."""
    try:
        port = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a port number (1-65535)") from None
    if not 1 <= port <= 65535:
        raise argparse.ArgumentTypeError(f"{port} is not a port number (1-65535)")
    return port


def _grade_outputs(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--thresholds", metavar="TOML", help="override rubric thresholds ([thresholds] table)"
    )
    p.add_argument("--json", metavar="PATH", help="write the grade as JSON")
    p.add_argument("--junit", metavar="PATH", help="write JUnit XML (a test case per rubric line)")
    p.add_argument("--csv", metavar="PATH", help="write CSV (a row per recording)")
    p.add_argument(
        "--overwrite", action="store_true", help="replace existing --json/--junit/--csv files"
    )


class _Parser(argparse.ArgumentParser):
    """argparse, but a bad command line is one ``usar: error:`` line and a hint (not a usage
    block), like every other user error."""

    def error(self, message: str) -> NoReturn:
        print(f"usar: error: {message}; see `{self.prog} --help`", file=sys.stderr)
        raise SystemExit(EXIT_USAGE)


def _positive_seconds(text: str) -> float:
    """``--max-sim-time``: a finite number of seconds above 0 (nan, 0 and -1 are refused)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of seconds") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"{text!r}: expected seconds above 0, e.g. 60")
    return value


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="usar",
        description=(
            "Run, record, replay, grade and view the two-robot US&R mission "
            "(ENPM809Y 'US&R Simplified') without ROS."
        ),
        epilog=(
            "Exit codes: 0 ok, 1 a check failed, 2 usage error, 3 incomplete or corrupt log, "
            "4 the mission's code failed, 130/143/129 interrupted by SIGINT/SIGTERM/SIGHUP."
        ),
    )
    parser.add_argument("--version", action="version", version=f"usar-replay {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    p = sub.add_parser("record", help="run the mission in pybullet and record it to MCAP")
    p.add_argument("--scenario", metavar="FILE", help="scenario TOML (default: the course world)")
    p.add_argument("--seed", type=int, help="a seeded variant: markers moved, targets recomputed")
    p.add_argument(
        "--assignment",
        choices=["usar", "ros2-final"],
        help="the built-in world of this assignment (default usar; a scenario file names its own)",
    )
    p.add_argument("--out", metavar="PATH", help="output .mcap (default: recordings/NAME.mcap)")
    p.add_argument("--camera", metavar="WxH@HZ", help="camera size and rate, e.g. 640x480@10")
    p.add_argument("--encoding", choices=["png", "jpeg"], help="recorded frame encoding")
    p.add_argument(
        "--renderer", choices=["auto", "tiny", "egl"], default="auto", help="pybullet renderer"
    )
    p.add_argument(
        "--max-sim-time", type=_positive_seconds, metavar="S", help="hard stop in sim seconds (>0)"
    )
    p.add_argument("--quiet", action="store_true", help="no progress line")
    _mission_options(p, replay=False)
    p.add_argument("--overwrite", action="store_true", help="replace an existing output file")
    p.set_defaults(func=_cmd_record)

    p = sub.add_parser("replay", help="re-run the mission from a log and compare its outputs")
    p.add_argument("file", metavar="FILE")
    p.add_argument("--grade", action="store_true", help="then grade the replayed outputs")
    p.add_argument(
        "--expect-changes",
        action="store_true",
        help="report differences without failing (regression runs of changed code or settings)",
    )
    _mission_options(p, replay=True)
    _grade_outputs(p)
    p.set_defaults(func=_cmd_replay)

    p = sub.add_parser("grade", help="grade recordings against the course rubric")
    p.add_argument("files", nargs="+", metavar="FILE|DIR")
    p.add_argument("--jobs", type=int, default=1, metavar="N", help="grade N files in parallel")
    p.add_argument(
        "--details", action="store_true", help="the full table of every recording of a batch"
    )
    _grade_outputs(p)
    p.set_defaults(func=_cmd_grade)

    p = sub.add_parser("report", help="write an HTML page per recording (map, rubric, frames)")
    p.add_argument("files", nargs="+", metavar="FILE|DIR")
    p.add_argument("-o", "--out", required=True, metavar="DIR", help="folder for the pages")
    p.add_argument(
        "--thresholds", metavar="TOML", help="override rubric thresholds ([thresholds] table)"
    )
    p.add_argument("--overwrite", action="store_true", help="replace existing pages")
    p.set_defaults(func=_cmd_report)

    p = sub.add_parser(
        "batch", help="grade a class: every team's mission on every world, resumably"
    )
    p.add_argument("submissions", metavar="SUBMISSIONS_DIR", help="a .py file or folder per team")
    p.add_argument("--seeds", metavar="N-M", help="seeded variants of the course world, e.g. 0-4")
    p.add_argument(
        "--scenario", nargs="+", action="extend", metavar="FILE", help="scenario TOML worlds"
    )
    p.add_argument("-o", "--out", required=True, metavar="OUT_DIR", help="the batch's folder")
    p.add_argument("--jobs", type=int, metavar="N", help="runs at a time (default: one per core)")
    p.add_argument("--engine", choices=["local", "ray"], default="local", help="where runs run")
    p.add_argument("--address", metavar="ADDR", help="Ray cluster address (--engine ray)")
    p.add_argument("--settings", metavar="TOML", help="settings from [record]/[mission]/[detector]")
    p.add_argument("--set", action="append", metavar="NAME=VALUE", help="a setting (as record)")
    p.add_argument("--max-sim-time", type=float, metavar="S", help="hard stop in sim seconds")
    p.add_argument(
        "--thresholds", metavar="TOML", help="override rubric thresholds ([thresholds] table)"
    )
    p.add_argument(
        "--tick-timeout", type=float, default=10.0, metavar="S", help="wall s per tick (10)"
    )
    p.add_argument(
        "--mission-memory", type=int, default=4096, metavar="MIB", help="MiB (4096; 0: none)"
    )
    p.add_argument(
        "--cpu-limit", type=int, default=1800, metavar="S", help="mission CPU s (1800; 0: none)"
    )
    p.add_argument(
        "--wall-limit", type=float, default=3600.0, metavar="S", help="wall s per run (3600)"
    )
    p.add_argument("--no-sandbox", action="store_true", help="let missions read other teams' files")
    p.add_argument("--gradescope", action="store_true", help="write TEAM/results.json per team")
    p.add_argument(
        "--visibility",
        choices=["visible", "hidden", "after_due_date", "after_published"],
        default="visible",
        help="Gradescope visibility of the tests (visible)",
    )
    p.add_argument("--quiet", action="store_true", help="no progress bar or per-run lines")
    p.set_defaults(func=_cmd_batch)

    p = sub.add_parser("view", help="show a recording's timeline in the rerun viewer")
    p.add_argument("file", metavar="FILE")
    p.add_argument(
        "--save", metavar="OUT.rrd", help="write an .rrd (default without a display: FILE.rrd)"
    )
    p.add_argument("--web", action="store_true", help="serve the web viewer until Ctrl-C")
    p.add_argument("--grade", action="store_true", help="add the rubric lines to the log view")
    p.add_argument("--web-port", type=_port, default=9090, metavar="N", help="web viewer port")
    p.add_argument(
        "--grpc-port", type=_port, default=9876, metavar="N", help="viewer data (gRPC) port"
    )
    p.add_argument(
        "--bind",
        type=_address,
        default="127.0.0.1",
        metavar="ADDR",
        help="address both viewer ports listen on (0.0.0.0: every interface; default 127.0.0.1)",
    )
    p.add_argument("--overwrite", action="store_true", help="replace an existing .rrd")
    p.set_defaults(func=_cmd_view)

    p = sub.add_parser(
        "scenario", help="print a world as TOML (the course, a seeded variant, or a checked file)"
    )
    p.add_argument("--scenario", metavar="FILE", help="scenario TOML to read (default: the course)")
    p.add_argument("--seed", type=int, help="a seeded variant: markers moved, targets recomputed")
    p.add_argument(
        "--assignment",
        choices=["usar", "ros2-final"],
        help="the built-in world of this assignment (default usar; a scenario file names its own)",
    )
    p.add_argument("--camera", metavar="WxH@HZ", help="camera size and rate, e.g. 640x480@10")
    p.add_argument("--encoding", choices=["png", "jpeg"], help="recorded frame encoding")
    p.add_argument("--out", metavar="FILE", help="write the TOML here instead of stdout")
    p.add_argument("--overwrite", action="store_true", help="replace an existing output file")
    p.add_argument(
        "--check",
        action="store_true",
        help="check that the world can be completed (prints a verdict; exit 1 if it cannot)",
    )
    p.set_defaults(func=_cmd_scenario)

    p = sub.add_parser("info", help="summarise and check a recording (topics, state, outcome)")
    p.add_argument("files", nargs="+", metavar="FILE", help="one or more .mcap files")
    p.add_argument(
        "--quick", action="store_true", help="trust the summary: do not check the data's CRCs"
    )
    p.set_defaults(func=_cmd_info)

    p = sub.add_parser(
        "recover", help="turn a killed recording's .part (or a damaged log) into a whole log"
    )
    p.add_argument("file", metavar="FILE", help="the .part or damaged .mcap")
    p.add_argument(
        "-o", "--out", metavar="OUT", help="output (default: FILE without .part, or X.recovered)"
    )
    p.add_argument("--overwrite", action="store_true", help="replace an existing output file")
    p.set_defaults(func=_cmd_recover)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``usar`` console script; returns the process exit code."""
    from usar_replay.core import signals

    with signals.handled():
        try:
            parser = _parser()
            args = parser.parse_args(argv)
            code: int = args.func(args)
        except UsarError as err:
            print(f"usar: error: {err}", file=sys.stderr)
            return err.exit_code
        except KeyboardInterrupt as err:
            # a plain Ctrl-C is "interrupted"; SIGTERM/SIGHUP say which signal ended the command
            code = signals.exit_code(err)
            text = str(err) if code != EXIT_INTERRUPTED else "interrupted"
            print(f"usar: {text}", file=sys.stderr)
            return code
        except BrokenPipeError:
            return EXIT_OK
    return code


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
