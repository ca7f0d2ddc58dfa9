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
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from usar_replay import __version__
from usar_replay.errors import NotBuiltYet, UsageError, UsarError

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


def _reports_out(args: argparse.Namespace, reports: list[GradeReport]) -> None:
    from usar_replay import reports as rep

    for path, fmt in ((args.json, rep.to_json), (args.junit, rep.to_junit), (args.csv, rep.to_csv)):
        if path:
            Path(path).write_text(fmt(reports))


def _thresholds(args: argparse.Namespace) -> Thresholds | None:
    from usar_replay.grade import load_thresholds

    return load_thresholds(args.thresholds) if args.thresholds else None


def _grade_one(path: str, thresholds: Thresholds | None) -> GradeReport | str:
    from usar_replay.grade import grade_file

    try:
        return grade_file(path, thresholds)
    except UsarError as err:
        return str(err)


def _cmd_grade(args: argparse.Namespace) -> int:
    from concurrent.futures import ProcessPoolExecutor

    from usar_replay.reports import to_table

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
        with ProcessPoolExecutor(max_workers=args.jobs) as pool:
            results = list(pool.map(_grade_one, files, [th] * len(files)))
    else:
        results = [_grade_one(f, th) for f in files]
    reports = [r for r in results if not isinstance(r, str)]
    errors = [r for r in results if isinstance(r, str)]
    for r in reports:
        print(to_table(r))
        print()
    for e in errors:
        print(f"usar: error: {e}", file=sys.stderr)
    _reports_out(args, reports)
    if len(files) > 1:
        passed = sum(r.passed for r in reports)
        print(f"{passed}/{len(files)} recordings pass")
    if errors:
        return EXIT_INCOMPLETE
    if any(not r.log_complete for r in reports):
        return EXIT_INCOMPLETE
    return EXIT_OK if all(r.passed for r in reports) else EXIT_FAIL


def _cmd_replay(args: argparse.Namespace) -> int:
    from usar_replay.grade import Grader
    from usar_replay.mission import MissionSettings
    from usar_replay.replay import apply_overrides, replay, settings_from_toml
    from usar_replay.reports import to_table

    settings = MissionSettings()
    if args.settings:
        settings = settings_from_toml(args.settings, settings)
    overrides: dict[str, str] = {}
    for item in args.set or []:
        if "=" not in item:
            raise UsageError(
                f"--set {item!r}: expected NAME=VALUE, e.g. detector.dictionary=DICT_5X5_50"
            )
        k, v = item.split("=", 1)
        overrides[k.strip()] = v.strip()
    settings = apply_overrides(settings, overrides)
    regression = bool(overrides or args.settings)
    grader: Grader | None = None
    sink = None
    if args.grade:
        from usar_replay import bag
        from usar_replay.replay import load_scenario

        grader = Grader(load_scenario(bag.BagReader(args.file)), _thresholds(args))
        sink = grader.feed
    report = replay(args.file, settings, grade_sink=sink, regression=regression)
    print("\n".join(report.lines()))
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
            code = max(code, EXIT_FAIL)
    if report.log_problem:
        print(f"usar: the log is incomplete: {report.log_problem}", file=sys.stderr)
        return EXIT_INCOMPLETE
    return code


def _not_built(name: str) -> Callable[[argparse.Namespace], int]:
    def run(args: argparse.Namespace) -> int:
        raise NotBuiltYet(
            f"`usar {name}` is not built yet in usar-replay {__version__}; "
            "see the README for what works today"
        )

    return run


def _grade_outputs(p: argparse.ArgumentParser) -> None:
    p.add_argument("--thresholds", metavar="TOML", help="override rubric thresholds")
    p.add_argument("--json", metavar="PATH", help="write the grade as JSON")
    p.add_argument("--junit", metavar="PATH", help="write JUnit XML (a test case per line)")
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
    p.set_defaults(func=_cmd_record)

    p = sub.add_parser("replay", help="re-run detector/tf/follower from a log and compare")
    p.add_argument("file", metavar="FILE")
    p.add_argument("--grade", action="store_true", help="then grade the replayed outputs")
    p.add_argument(
        "--set", action="append", metavar="NAME=VALUE", help="changed setting (regression mode)"
    )
    p.add_argument("--settings", metavar="TOML", help="changed settings from a TOML file")
    _grade_outputs(p)
    p.set_defaults(func=_cmd_replay)

    p = sub.add_parser("grade", help="grade recordings against the course rubric")
    p.add_argument("files", nargs="+", metavar="FILE|DIR")
    p.add_argument("--jobs", type=int, default=1, metavar="N", help="grade N files in parallel")
    _grade_outputs(p)
    p.set_defaults(func=_cmd_grade)

    p = sub.add_parser("view", help="show a recording's timeline in the rerun viewer")
    p.add_argument("file")
    p.set_defaults(func=_not_built("view"))

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
