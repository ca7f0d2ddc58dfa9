"""The `usar` command: arguments, messages to people, exit codes.

Exit codes (the same for every subcommand):

* 0 - done; for grading: every required rubric line passed.
* 1 - a rubric line or the replay comparison failed.
* 2 - usage error: bad option, bad scenario file, a command not built yet.
* 3 - the log is incomplete or corrupt (what could be read was still used, and said so).
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

__all__ = ["main"]

EXIT_OK = 0
EXIT_FAIL = 1
EXIT_USAGE = 2
EXIT_INCOMPLETE = 3
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
        self.tty = sys.stderr.isatty()
        self.last_print = -1e9

    def __call__(self, p: Progress) -> None:
        text = (
            f"sim {p.sim_time_s:7.1f} s | {p.phase.value:<32} | markers {p.markers_found}/"
            f"{p.markers_total} | frames {p.frames}"
        )
        if self.tty:
            if p.sim_time_s - self.last_print >= 0.5:
                print("\r" + text, end="", file=sys.stderr, flush=True)
                self.last_print = p.sim_time_s
        elif p.sim_time_s - self.last_print >= 30.0:
            print(text, file=sys.stderr, flush=True)
            self.last_print = p.sim_time_s

    def close(self) -> None:
        if self.tty:
            print(file=sys.stderr)


def _cmd_record(args: argparse.Namespace) -> int:
    from usar_replay.record import RecordSettings, default_output, print_summary, record

    scenario = _load_scenario(args)
    out = Path(args.out) if args.out else default_output(scenario)
    if out.exists() and not args.overwrite:
        raise UsageError(f"{out} exists; pass --overwrite to replace it, or --out another path")
    settings = RecordSettings(renderer=args.renderer, max_sim_time_s=args.max_sim_time)
    status = _StatusLine()
    try:
        result = record(scenario, out, settings, progress=None if args.quiet else status)
    except KeyboardInterrupt:
        status.close()
        print(
            f"usar: interrupted; {out} is closed and readable, marked interrupted",
            file=sys.stderr,
        )
        return EXIT_INTERRUPTED
    status.close()
    print_summary(result)
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
    from usar_replay.mission import MissionSettings
    from usar_replay.replay import apply_overrides, replay, settings_from_toml
    from usar_replay.reports import to_table

    if args.jobs is not None and args.jobs < 0:
        raise UsageError(f"--jobs {args.jobs}: expected 0 or more")
    settings = MissionSettings()
    if args.settings:
        settings = settings_from_toml(args.settings, settings)
    overrides: dict[str, str] = {}
    for item in args.set or []:
        k, eq, v = item.partition("=")
        if not eq or not k.strip():
            raise UsageError(
                f"--set {item!r}: expected NAME=VALUE, e.g. detector.dictionary=DICT_5X5_50"
            )
        overrides[k.strip()] = v.strip()
    settings = apply_overrides(settings, overrides)
    regression = bool(overrides or args.settings)
    thresholds = _thresholds(args)  # a bad thresholds file is a usage error before any work
    grader: Grader | None = None
    if args.grade:
        from usar_replay import bag
        from usar_replay.replay import load_scenario

        grader = Grader(load_scenario(bag.BagReader(args.file)), thresholds)
    report = replay(
        args.file,
        settings,
        grade_sink=None if grader is None else grader.feed,
        grade_topics=GRADE_TOPICS,
        required_topics=REQUIRED_TOPICS if grader is not None else (),
        regression=regression,
        workers=args.jobs,
    )
    print("\n".join(report.lines()))
    # regression mode expects differences: it reports them, and only grading can fail it
    code = EXIT_OK if (report.identical or regression) else EXIT_FAIL
    if grader is not None:
        g = grader.report(
            f"{args.file} (replayed)",
            log_complete=not report.log_problem,
            log_problem=report.log_problem,
        )
        print()
        print(to_table(g))
        _reports_out(args, [g])
        if not g.passed:
            code = EXIT_FAIL
    if report.log_problem:
        print(
            f"usar: {args.file}: the log is incomplete ({report.log_problem}); "
            "replayed as far as it goes",
            file=sys.stderr,
        )
        return EXIT_INCOMPLETE
    return code


def _cmd_view(args: argparse.Namespace) -> int:
    import os

    # rerun's own log lines (a failed file write is two ERROR lines from its writer thread) would
    # break the one-line error contract; the failure itself still raises and is reported below
    os.environ.setdefault("RUST_LOG", "off")
    from usar_replay.run import open_run
    from usar_replay.view import (
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


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="usar",
        description=(
            "Run, record, replay, grade and view the two-robot US&R mission "
            "(ENPM809Y 'US&R Simplified') without ROS."
        ),
        epilog="Exit codes: 0 ok, 1 a check failed, 2 usage error, 3 incomplete or corrupt log.",
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
    p.add_argument("--overwrite", action="store_true", help="replace an existing output file")
    p.set_defaults(func=_cmd_record)

    p = sub.add_parser("replay", help="re-run detector/tf/follower from a log and compare")
    p.add_argument("file", metavar="FILE")
    p.add_argument("--grade", action="store_true", help="then grade the replayed outputs")
    p.add_argument(
        "--set", action="append", metavar="NAME=VALUE", help="changed setting (regression mode)"
    )
    p.add_argument("--settings", metavar="TOML", help="changed settings from a TOML file")
    p.add_argument(
        "--jobs",
        type=int,
        metavar="N",
        help="detector threads ahead of the mission (default: one per core, up to 4; 0: none)",
    )
    _grade_outputs(p)
    p.set_defaults(func=_cmd_replay)

    p = sub.add_parser("grade", help="grade recordings against the course rubric")
    p.add_argument("files", nargs="+", metavar="FILE|DIR")
    p.add_argument("--jobs", type=int, default=1, metavar="N", help="grade N files in parallel")
    _grade_outputs(p)
    p.set_defaults(func=_cmd_grade)

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
