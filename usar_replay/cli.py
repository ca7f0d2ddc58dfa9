"""The `usar` command: arguments, messages to people, exit codes.

Exit codes (the same for every subcommand):

* 0 - done; for grading: every required rubric line passed.
* 1 - a rubric line or the replay comparison failed.
* 2 - usage error: bad option, bad scenario file, a command not built yet.
* 3 - the log is incomplete or corrupt (what could be read was still used, and said so).
* 4 - the mission's code crashed, hung, ran out of memory or published what it may not (the
  log is closed and records the verdict; the user's traceback is shown).
* 130 - interrupted by Ctrl-C (a recording is still closed and readable).

User errors (:class:`usar_replay.errors.UsarError`) are printed as one line, ``usar: error: ...``,
without a traceback; anything else is a bug and raises.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from usar_replay import __version__
from usar_replay.errors import UsageError, UsarError

if TYPE_CHECKING:
    from usar_replay.grade import GradeReport, Thresholds
    from usar_replay.record import Progress
    from usar_replay.scenario import Scenario
    from usar_replay.settings import RunSettings
    from usar_replay.worker import MissionLimits

__all__ = ["main"]

EXIT_OK = 0
EXIT_FAIL = 1
EXIT_USAGE = 2
EXIT_INCOMPLETE = 3
EXIT_MISSION = 4
EXIT_INTERRUPTED = 130


def _cmd_info(args: argparse.Namespace) -> int:
    from usar_replay.info import describe, read_info

    worst = EXIT_OK
    for i, path in enumerate(args.files):
        info = read_info(path)
        if i:
            print()
        print(describe(info))
        if not info.complete:
            worst = EXIT_INCOMPLETE
    return worst


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
    from usar_replay import scenario as scn

    base = scn.load(args.scenario) if args.scenario else scn.course_world()
    if args.seed is not None:
        from usar_replay.variants import make_variant

        base = make_variant(base, args.seed)
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
    from usar_replay.scenario import to_toml

    scenario = _load_scenario(args)
    text = to_toml(scenario)
    if args.out:
        out = Path(args.out)
        if out.exists() and not args.overwrite:
            raise UsageError(f"{out} exists; pass --overwrite to replace it, or --out another path")
        out.write_text(text, encoding="utf-8")
        print(f"wrote {out}: {scenario.summary().splitlines()[0]}", file=sys.stderr)
    else:
        print(text, end="")
    if not args.check:
        return EXIT_OK
    from usar_replay.variants import MAX_DRIVE_FRACTION, check_variant, drive_time_s

    problem = check_variant(scenario)
    if problem is not None:
        print(f"usar: {scenario.name}: fails the variant rules: {problem}", file=sys.stderr)
        return EXIT_FAIL
    need = drive_time_s(scenario)
    print(
        f"usar: {scenario.name}: every target sees its own marker within range, every goal is "
        f"reachable, driving takes {need:.0f} s of the {MAX_DRIVE_FRACTION:.0%} "
        f"({MAX_DRIVE_FRACTION * scenario.time_limit_s:.0f} s) allowed",
        file=sys.stderr,
    )
    return EXIT_OK


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
    from usar_replay import settings as settings_mod

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
    from usar_replay.worker import MissionLimits

    if not (args.tick_timeout > 0):
        raise UsageError(f"--tick-timeout {args.tick_timeout}: expected a positive number of s")
    if args.mission_memory < 0:
        raise UsageError(f"--mission-memory {args.mission_memory}: expected MiB >= 0 (0: none)")
    return MissionLimits(tick_timeout_s=args.tick_timeout, memory_mb=args.mission_memory)


def _cmd_record(args: argparse.Namespace) -> int:
    from usar_replay.record import default_output, print_summary, record
    from usar_replay.settings import RunSettings

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
    try:
        result = record(
            scenario,
            out,
            settings,
            progress=None if args.quiet else status,
            mission=args.mission,
            limits=_limits(args),
        )
    except KeyboardInterrupt:
        status.close()
        what = (
            f"{out} is closed and readable, marked interrupted"
            if out.exists()
            else ("nothing was written")
        )
        print(f"usar: interrupted; {what}", file=sys.stderr)
        return EXIT_INTERRUPTED
    status.close()
    print_summary(result)
    if result.outcome in ("crashed", "hung", "out_of_memory", "refused"):
        return EXIT_MISSION
    return EXIT_OK if result.mission_done else EXIT_FAIL


def _reports_out(
    args: argparse.Namespace,
    reports: Sequence[GradeReport],
    errors: Sequence[tuple[str, str]] = (),
) -> None:
    """Write the machine-readable reports asked for; a recording that could not be graded at all
    is in them too (``errors``: (path, message)), so a CI run never loses one silently."""
    from usar_replay import reports as rep

    for opt, path, fmt in (
        ("--json", args.json, rep.to_json),
        ("--junit", args.junit, rep.to_junit),
        ("--csv", args.csv, rep.to_csv),
    ):
        if path:
            try:
                Path(path).write_text(fmt(reports, errors), encoding="utf-8")
            except OSError as err:
                raise UsageError(f"{opt} {path}: cannot write: {err.strerror or err}") from err


def _thresholds(args: argparse.Namespace) -> Thresholds | None:
    from usar_replay.grade import load_thresholds

    return load_thresholds(args.thresholds) if args.thresholds else None


def _grade_one(path: str, thresholds: Thresholds | None) -> GradeReport | tuple[str, int]:
    """Grade one file; a user error becomes (message, exit code) so one bad file among many is
    one line, not the end of the batch (and so it crosses a process boundary as plain data)."""
    from usar_replay.grade import grade_file

    try:
        return grade_file(path, thresholds)
    except UsarError as err:
        return (str(err), err.exit_code)


def _cmd_grade(args: argparse.Namespace) -> int:
    from concurrent.futures import ProcessPoolExecutor

    from usar_replay.reports import to_table

    if args.jobs < 1:
        raise UsageError(f"--jobs {args.jobs}: expected 1 or more")
    files: list[str] = []
    for name in args.files:
        p = Path(name)
        if p.is_dir():
            found = sorted(str(f) for f in p.glob("*.mcap"))
            if not found:
                raise UsageError(f"{p}: no .mcap files in this directory")
            files += found
        else:
            files.append(name)
    th = _thresholds(args)
    if args.jobs > 1 and len(files) > 1:
        with ProcessPoolExecutor(max_workers=min(args.jobs, len(files))) as pool:
            results = list(pool.map(_grade_one, files, [th] * len(files)))
    else:
        results = [_grade_one(f, th) for f in files]
    reports = [r for r in results if not isinstance(r, tuple)]
    errors = [(f, r[0]) for f, r in zip(files, results, strict=True) if isinstance(r, tuple)]
    for r in reports:
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
    _reports_out(args, reports, errors)
    if len(files) > 1:
        passed = sum(r.passed and r.log_complete for r in reports)
        print(f"{passed}/{len(files)} recordings pass")
    codes = [r[1] for r in results if isinstance(r, tuple)]
    if codes:
        return max(codes)
    if any(not r.log_complete for r in reports):
        return EXIT_INCOMPLETE
    return EXIT_OK if all(r.passed for r in reports) else EXIT_FAIL


def _cmd_replay(args: argparse.Namespace) -> int:
    from usar_replay.grade import GRADE_TOPICS, REQUIRED_TOPICS, Grader
    from usar_replay.replay import check_not_damaged, replay
    from usar_replay.reports import to_table
    from usar_replay.run import open_run

    run = open_run(args.file)
    changed = bool(args.set or args.settings)
    settings = _run_settings(args, run.settings) if changed else None
    thresholds = _thresholds(args)  # a bad thresholds file is a usage error before any work
    grader: Grader | None = None
    if args.grade:
        grader = Grader(run.require_scenario(), thresholds)
    report = replay(
        run,
        settings,
        mission=args.mission,
        grade_sink=None if grader is None else grader.feed,
        grade_topics=GRADE_TOPICS,
        required_topics=REQUIRED_TOPICS if grader is not None else (),
        limits=_limits(args),
    )
    check_not_damaged(report)
    print("\n".join(report.lines()))
    code = EXIT_OK if report.identical or args.expect_changes else EXIT_FAIL
    if report.mission_failure is not None:
        code = EXIT_MISSION
    if grader is not None:
        g = grader.report(
            f"{args.file} (replayed)",
            log_complete=not report.log_problem,
            log_problem=report.log_problem,
        )
        print()
        print(to_table(g))
        _reports_out(args, [g])
        if not g.passed and code == EXIT_OK:
            code = EXIT_FAIL
    if report.log_problem:
        print(
            f"usar: {args.file}: the log is incomplete ({report.log_problem}); "
            "replayed as far as it goes",
            file=sys.stderr,
        )
        return EXIT_INCOMPLETE
    return code


def _cmd_batch(args: argparse.Namespace) -> int:
    """``usar batch``: every team's mission on every world, recorded, graded, summarised."""
    import dataclasses as dc
    import os

    from usar_replay.batch import Limits, parse_seeds
    from usar_replay.batch_main import grade_class, plan_class
    from usar_replay.engines import make_engine
    from usar_replay.settings import RunSettings
    from usar_replay.settings import to_toml as settings_to_toml

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

    from usar_replay.view import choose_output, open_command, view_file, wait_until_interrupted

    output = choose_output(args.file, save=args.save, web=args.web, env=os.environ)
    result = view_file(
        args.file, output, grade=args.grade, grpc_port=args.grpc_port, web_port=args.web_port
    )
    if result.rrd is not None:
        print(
            f"wrote {result.rrd} ({result.frames} camera frames, {result.messages} messages, "
            f"{result.seconds:.1f} s); open it with:"
        )
        print(open_command(result.rrd))
    if result.spawned:
        print(f"sent {args.file} to the rerun viewer ({result.frames} camera frames)")
    if result.viewer_problem:
        print(f"usar: {result.viewer_problem}; wrote the view to a file", file=sys.stderr)
    problems = [f"the log is incomplete ({result.problem})"] if result.problem else []
    problems += [result.grade_problem] if result.grade_problem else []
    if problems:
        text = "; ".join(problems)
        print(f"usar: {args.file}: {text}; the view shows what was read", file=sys.stderr)
    if result.url:
        print(f"serving the web viewer at {result.url} (Ctrl-C to stop)", flush=True)
        wait_until_interrupted(result)
    return EXIT_INCOMPLETE if problems else EXIT_OK


def _grade_outputs(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--thresholds", metavar="TOML", help="override rubric thresholds ([thresholds] table)"
    )
    p.add_argument("--json", metavar="PATH", help="write the grade as JSON")
    p.add_argument("--junit", metavar="PATH", help="write JUnit XML (a test case per rubric line)")
    p.add_argument("--csv", metavar="PATH", help="write CSV (a row per recording)")


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="usar",
        description=(
            "Run, record, replay, grade and view the two-robot US&R mission "
            "(ENPM809Y 'US&R Simplified') without ROS."
        ),
        epilog=(
            "Exit codes: 0 ok, 1 a check failed, 2 usage error, 3 incomplete or corrupt log, "
            "4 the mission's code failed, 130 interrupted."
        ),
    )
    parser.add_argument("--version", action="version", version=f"usar-replay {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    p = sub.add_parser("record", help="run the mission in pybullet and record it to MCAP")
    p.add_argument("--scenario", metavar="FILE", help="scenario TOML (default: the course world)")
    p.add_argument("--seed", type=int, help="a seeded variant: markers moved, targets recomputed")
    p.add_argument("--out", metavar="PATH", help="output .mcap (default: recordings/NAME.mcap)")
    p.add_argument("--camera", metavar="WxH@HZ", help="camera size and rate, e.g. 640x480@10")
    p.add_argument("--encoding", choices=["png", "jpeg"], help="recorded frame encoding")
    p.add_argument(
        "--renderer", choices=["auto", "tiny", "egl"], default="auto", help="pybullet renderer"
    )
    p.add_argument("--max-sim-time", type=float, metavar="S", help="hard stop in sim seconds")
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
    _grade_outputs(p)
    p.set_defaults(func=_cmd_grade)

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
    p.add_argument("--web-port", type=int, default=9090, metavar="N", help="web viewer port")
    p.add_argument("--grpc-port", type=int, default=9876, metavar="N", help="viewer gRPC port")
    p.set_defaults(func=_cmd_view)

    p = sub.add_parser(
        "scenario", help="print a world as TOML (the course, a seeded variant, or a checked file)"
    )
    p.add_argument("--scenario", metavar="FILE", help="scenario TOML to read (default: the course)")
    p.add_argument("--seed", type=int, help="a seeded variant: markers moved, targets recomputed")
    p.add_argument("--camera", metavar="WxH@HZ", help="camera size and rate, e.g. 640x480@10")
    p.add_argument("--encoding", choices=["png", "jpeg"], help="recorded frame encoding")
    p.add_argument("--out", metavar="FILE", help="write the TOML here instead of stdout")
    p.add_argument("--overwrite", action="store_true", help="replace an existing output file")
    p.add_argument(
        "--check", action="store_true", help="also check the variant rules (exit 1 if one fails)"
    )
    p.set_defaults(func=_cmd_scenario)

    p = sub.add_parser("info", help="summarise a recording (topics, counts, scenario, status)")
    p.add_argument("files", nargs="+", metavar="FILE", help="one or more .mcap files")
    p.set_defaults(func=_cmd_info)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``usar`` console script; returns the process exit code."""
    parser = _parser()
    args = parser.parse_args(argv)
    try:
        code: int = args.func(args)
    except UsarError as err:
        print(f"usar: error: {err}", file=sys.stderr)
        return err.exit_code
    except KeyboardInterrupt:
        print("usar: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:
        return EXIT_OK
    return code


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
