"""A class's ROS 1 packages on the course world, at a glance (printed, never asserted).

    python bench/bench_class.py [FOLDER] [--world course|room] [--max-sim-time S] [--keep DIR]
                                [--no-compare] [--with-idle SHAPE]
    python bench/bench_class.py --logs DIR        # grade kept logs again: rubric v2 against v3

Each sub-folder of FOLDER (default: examples/ros1) that holds one catkin package is built and
recorded as ``usar record --ros1 PKG`` does it (catkin_make into the build cache, the package's
launch file, usar's simulator, move_base and aruco_detect in the course's place), and its log
graded as ``usar grade`` does it, one package after the other. Then one row per package:

* ``built``: ``catkin_make``'s wall seconds, ``cached``, or ``FAILED``;
* ``outcome``: how the run ended (``done``, ``time_limit``, ``crashed``, ``build_failed``, ...);
* ``verdict``, ``points``: the rubric's (docs/reports.md), PASS only with every required line;
* ``sim s``: the run's sim time; ``wall s``: build + run + grade, the instructor's wait;
* ``failed lines``: the ids of the rubric lines that failed (wrapped under the column);
* under each row, ``start:`` the command the package was started with and where it was read
  (``doc/instructions.txt line 3``, ``README.md``, the package's only launch file, ...).

``--with-idle SHAPE`` adds the package of ``tests/idle_package.py`` (a node that idles after a
short mission, ``silent``: a busy wait with no call, as a team whose last goal aborted) as one
more team, started as its ``doc/instructions.txt`` says: a team that never ends by itself.

Why a script and not ``usar batch``: a batch grades Python and ROS 1 teams on many worlds into a
folder of files; this is the one-screen view of a folder of packages on one world, for
docs/ros1.md and for an instructor trying a class before the real batch. The logs go to a
temporary folder (``--keep DIR`` keeps them). The date, the machine's load average before and
after, and the CPU count are printed with the table: wall times depend on them.

Then the rubric's versions side by side (issue 43): each log graded by rubric usar v2 (its
module as it was at :data:`V2_COMMIT`, read with ``git show`` from this checkout's history, as
pure as v3) and by v3, one row per package with both totals and every line whose points
changed (``follower.marker_1 0->3``). ``--logs DIR`` does only this, on the ``.mcap`` files of a
folder (a ``--keep`` folder, or a batch's OUT_DIR: every ``*.mcap`` below it).
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import subprocess
import sys
import tempfile
import textwrap
import time
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

from usar_replay.core.errors import UsageError
from usar_replay.core.settings import RecordSettings, RunSettings
from usar_replay.grading.grade import GradeReport, grade_file, with_goal_tolerances
from usar_replay.log.run import open_run
from usar_replay.ros1.building import find_package
from usar_replay.ros1.record import record_ros1
from usar_replay.world.scenario import Scenario, course_world

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
import idle_package  # noqa: E402
from conftest import one_room  # noqa: E402

COLUMNS = (
    ("package", 16),
    ("built", 7),
    ("outcome", 12),
    ("verdict", 7),
    ("points", 7),
    ("sim s", 6),
    ("wall s", 6),
)
"""(header, width) of each fixed column, one space apart; ``failed lines`` takes the rest of
100 columns (32, enough for the longest rubric line id, ``marker_frame.only_on_detection``)."""
WIDTH = 100
V2_COMMIT = "11d80cc"
"""The last commit with rubric usar v2 (``usar_replay/grading/rubric_usar.py``)."""


@dataclass(frozen=True, slots=True)
class Row:
    """One package's result."""

    package: str
    built: str
    outcome: str
    verdict: str
    points: str
    sim_s: float
    wall_s: float
    failed: tuple[str, ...]
    start: str = ""
    """How it was started and where that was read (the grade's ``started_with``)."""


def packages(folder: Path) -> list[Path]:
    """The sub-folders of ``folder`` holding one catkin package each (sorted by name), or
    ``folder`` itself when it is a package."""
    if (folder / "package.xml").is_file():
        return [folder]
    out = []
    for sub in sorted(p for p in folder.iterdir() if p.is_dir()):
        try:
            find_package(sub)
        except UsageError:
            continue
        out.append(sub)
    return out


def run_one(scenario: Scenario, pkg: Path, out: Path, settings: RunSettings) -> Row:
    """Build, record and grade one package."""
    start = time.perf_counter()
    result = record_ros1(scenario, out, pkg, settings)
    report = grade_file(out)
    wall = time.perf_counter() - start
    if result.build == "failed":
        built = "FAILED"
    elif result.build == "cached":
        built = "cached"
    else:  # "catkin_make 14.2 s"
        built = result.build.removeprefix("catkin_make ").removesuffix(" s") + " s"
    return Row(
        package=pkg.name,
        built=built,
        outcome=result.outcome,
        verdict="PASS" if report.passed and report.log_complete else "FAIL",
        points=f"{report.points:.4g}/{report.max_points:.4g}",
        sim_s=result.sim_duration_s,
        wall_s=wall,
        failed=tuple(c.id for c in report.checks if not c.passed),
        start=report.started_with,
    )


def table(rows: list[Row]) -> list[str]:
    """The rows as lines of at most :data:`WIDTH` columns (failed lines wrap under their
    column)."""
    fixed = sum(w + 1 for _, w in COLUMNS)
    rest = WIDTH - fixed
    head = "".join(f"{h:<{w}} " for h, w in COLUMNS) + "failed lines"
    lines = [head, "-" * WIDTH]
    for r in rows:
        cells = (
            r.package[:16],
            r.built,
            r.outcome[:12],
            r.verdict,
            r.points,
            f"{r.sim_s:.1f}",
            f"{r.wall_s:.0f}",
        )
        left = "".join(f"{c:<{w}} " for c, (_, w) in zip(cells, COLUMNS, strict=True))
        wrapped = textwrap.wrap(
            ", ".join(r.failed) or "-", rest, break_on_hyphens=False, break_long_words=False
        )
        lines.append(left + wrapped[0])
        lines += [" " * fixed + more for more in wrapped[1:]]
        lines += textwrap.wrap(
            f"start: {r.start or '-'}", WIDTH, initial_indent="  ", subsequent_indent="    "
        )
    return lines


def rubric_v2() -> ModuleType:
    """Rubric usar v2 as it was at :data:`V2_COMMIT` (a module of its own, imported from the
    text ``git show`` gives: it imports only core, world and grading.verdict, which v3 kept)."""
    try:
        text = subprocess.run(
            ["git", "-C", str(ROOT), "show", f"{V2_COMMIT}:usar_replay/grading/rubric_usar.py"],
            capture_output=True,
            text=True,
            check=True,
        ).stdout
    except (OSError, subprocess.CalledProcessError) as err:
        sys.exit(f"usar: error: rubric v2 is read from git history ({V2_COMMIT}): {err}")
    scratch = Path(tempfile.mkdtemp(prefix="usar-rubric-v2-")) / "rubric_usar_v2.py"
    scratch.write_text(text, encoding="utf-8")
    spec = importlib.util.spec_from_file_location("rubric_usar_v2", scratch)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["rubric_usar_v2"] = module
    spec.loader.exec_module(module)
    return module


def grade_v2(v2: ModuleType, log: Path) -> GradeReport:
    """``log`` graded by rubric v2, fed as :func:`usar_replay.grading.grade.observe_run` feeds
    a rubric (the course's detections only as the world published them)."""
    run = open_run(log)
    grader: Any = v2.Grader(run.require_scenario(), with_goal_tolerances(None, run))
    grader.start_ns = run.start_ns
    trusted = {topic: ("sim",) for topic in v2.RUBRIC.trusted_topics}
    for topic, msg, t in run.reader.decoded(v2.GRADE_TOPICS, only_from=trusted):
        grader.feed(topic, msg, t)
    report: GradeReport = grader.report(str(log))
    return report


def compare(logs: list[Path]) -> list[str]:
    """One row per log: v2's and v3's totals and the lines whose points changed."""
    v2 = rubric_v2()
    lines = [f"{'package':<40} {'v2':>6} {'v3':>6}  lines that changed (v2 -> v3 points)"]
    lines.append("-" * WIDTH)
    for log in logs:
        old, new = grade_v2(v2, log), grade_file(log)
        before = {c.id: c.points for c in old.checks}
        changed = [
            f"{c.id} {before.get(c.id, 0):.3g}->{c.points:.3g}"
            for c in new.checks
            if abs(before.get(c.id, 0.0) - c.points) > 1e-9
        ]
        name = log.stem if log.parent.name in ("", ".") else f"{log.parent.name}/{log.stem}"
        left = f"{name[:40]:<40} {old.points:>6.4g} {new.points:>6.4g}  "
        wrapped = textwrap.wrap(", ".join(changed) or "-", WIDTH - len(left)) or ["-"]
        lines.append(left + wrapped[0])
        lines += [" " * len(left) + more for more in wrapped[1:]]
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", nargs="?", default=str(ROOT / "examples" / "ros1"))
    ap.add_argument("--logs", type=Path, help="only grade the .mcap files below DIR, v2 and v3")
    ap.add_argument("--world", choices=("course", "room"), default="course")
    ap.add_argument("--max-sim-time", type=float, help="stop each run at this sim time (s)")
    ap.add_argument("--keep", type=Path, help="write the logs into this folder and keep them")
    ap.add_argument("--no-compare", action="store_true", help="leave out rubric v2 against v3")
    ap.add_argument(
        "--with-idle",
        choices=idle_package.SHAPES,
        help="add tests/idle_package.py as a team started with this shape (not 'done': never ends)",
    )
    args = ap.parse_args()
    if args.logs is not None:
        found = sorted(args.logs.rglob("*.mcap"))
        if not found:
            sys.exit(f"usar: error: {args.logs}: no .mcap file below it")
        print("\n".join(compare(found)))
        return
    pkgs = packages(Path(args.folder))
    if args.with_idle:
        extra = Path(tempfile.mkdtemp(prefix="usar-bench-class-idle-")) / idle_package.NAME
        pkgs.append(idle_package.write(extra, default=args.with_idle))
    if not pkgs:
        sys.exit(f"usar: error: {args.folder}: no catkin package in it or in its sub-folders")
    scenario = course_world() if args.world == "course" else one_room()
    settings = RunSettings(record=RecordSettings(max_sim_time_s=args.max_sim_time))
    load0 = os.getloadavg()
    rows = []
    with tempfile.TemporaryDirectory(prefix="usar-bench-class-") as scratch:
        logs = args.keep or Path(scratch)
        logs.mkdir(parents=True, exist_ok=True)
        for pkg in pkgs:
            print(f"{pkg.name}: building and recording on the {args.world} world ...", flush=True)
            rows.append(run_one(scenario, pkg, logs / f"{pkg.name}.mcap", settings))
        load1 = os.getloadavg()
        print()
        print("\n".join(table(rows)))
        wall, sim = sum(r.wall_s for r in rows), sum(r.sim_s for r in rows)
        print(f"total: wall {wall:.0f} s, sim {sim:.0f} s")
        if not args.no_compare:
            print()
            print("\n".join(compare([logs / f"{pkg.name}.mcap" for pkg in pkgs])))
    print(
        f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, {args.world} world, "
        f"{os.cpu_count()} CPUs, load average {load0[0]:.1f} before, {load1[0]:.1f} after"
    )


if __name__ == "__main__":
    main()
