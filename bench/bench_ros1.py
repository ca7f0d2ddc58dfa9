"""`usar record --ros1`: build time and the real-time factor a C++ course node sustains.

    python bench/bench_ros1.py [--world room|course] [--rtf 0.5] [--package DIR]
                               [--launch FILE ...] [--latency 0|1] [--detection-latency 0|1]
                               [--course-detection on|off]

Builds the package once into an empty build cache (catkin_make: the build time), then records
it on the world with each ``--rtf`` wall cap (the slowest pace, a safety net: the graph itself
paces the clock, docs/ros1.md), reusing that build, and prints per run: the outcome, the
rubric's points, sim time, wall time and the real-time factor reached (sim / wall), and the
whole build + run + grade time.

Each ``--launch`` file is one run (the example package's default: ``usar_course.launch``, a
``ros::Rate`` loop, and its busy twins ``busy_scan.launch`` and ``busy_wait.launch``, the same
logic polling without sleeping: each busy run's wall time is printed as a ratio to the Rate
run's, which issue 31 wants within 1.5x). The built-in Python mission is recorded on the same
world before the first ROS 1 run and again after each, and each ROS 1 run's real-time factor
is printed beside the mean of the Python runs just before and after it (the ratio issue 31
wants at 0.8 or more): a shared machine's speed drifts by 10-20% over the minutes a
course-world bench takes (one Python run went from 6.4x to 7.7x within six minutes), and
Python runs at the ends only would put the drift into the ratios of the runs in the middle.
The ROS 1 runs use ``record.actuation_latency_ticks`` as ``usar record --ros1`` does (unset:
1, the graph reacts while the simulator steps the next tick); ``--latency 0`` measures them
one core at a time, as before 2026-11-27. Likewise ``record.detection_latency_ticks`` (unset:
1, the course's detections of a frame come with the next tick); ``--detection-latency 0``
measures them in the frame's own tick, as before. The Python runs always use their own
defaults, 0 and 0 (bench/bench_record.py: with 1 the Python mission was slower).
``--course-detection`` sets ``record.course_detection`` for both (issue 43: the course's
detector at the course camera's 1920x1080, from regions the recorder renders; default on).
Nothing is asserted; the numbers go into docs/ros1.md.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import textwrap
import time
from pathlib import Path

from usar_replay.core.settings import RecordSettings, RunSettings
from usar_replay.grading.grade import grade_file
from usar_replay.log.run import open_run
from usar_replay.pipeline import record as python_record
from usar_replay.process.mission_process import MissionLimits, uses_kernel_sandbox
from usar_replay.ros1.building import workspace as build_mod
from usar_replay.ros1.process import Ros1Options
from usar_replay.ros1.record import record_ros1
from usar_replay.world.scenario import Scenario, course_world

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from conftest import one_room

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "ros1" / "usar_course"
TWINS = ["usar_course.launch", "busy_scan.launch", "busy_wait.launch"]
"""The example package's Rate loop first, then the same logic polling without sleeping."""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--world", choices=["room", "course"], default="room")
    ap.add_argument("--rtf", type=float, nargs="+", default=[0.5])
    ap.add_argument("--package", default=str(EXAMPLE))
    ap.add_argument("--launch", nargs="+", help="launch files (default: the example's twins)")
    ap.add_argument(
        "--latency", type=int, choices=[0, 1], help="the ROS 1 runs' actuation latency (ticks)"
    )
    ap.add_argument(
        "--detection-latency",
        type=int,
        choices=[0, 1],
        help="the ROS 1 runs' detection latency (ticks)",
    )
    ap.add_argument(
        "--course-detection",
        choices=["on", "off"],
        help="record.course_detection for both missions (default: the recorder's)",
    )
    args = ap.parse_args()
    course = None if args.course_detection is None else args.course_detection == "on"
    _COURSE[0] = course
    ros1_settings = RunSettings(
        record=RecordSettings(
            actuation_latency_ticks=args.latency,
            detection_latency_ticks=args.detection_latency,
            **({} if course is None else {"course_detection": course}),
        )
    )
    launches = args.launch or (TWINS if Path(args.package) == EXAMPLE else [""])
    scenario = one_room() if args.world == "room" else course_world()
    with tempfile.TemporaryDirectory(prefix="bench-ros1-") as tmp:
        os.environ["XDG_CACHE_HOME"] = tmp  # a cold build, then the runs reuse it
        pkg = build_mod.find_package(args.package)
        t0 = everything = time.perf_counter()
        cpu0 = _children_cpu()
        # built as the recording will want it (at the sandbox's fixed paths when there is one)
        build_mod.cached_build(pkg, fixed=uses_kernel_sandbox(MissionLimits()))
        say(
            f"build: {time.perf_counter() - t0:.1f} s wall, {_children_cpu() - cpu0:.1f} s CPU"
            f" (catkin_make -j2, {pkg.name} + fiducial_msgs)"
        )
        python = _python_rtf(scenario, Path(tmp) / "python-0.mcap", "before the first")
        ros1: list[tuple[str, float, float]] = []  # (what, sim / wall, Python's beside it)
        for rtf in args.rtf:
            rate_wall = 0.0
            for launch in launches:
                out = Path(tmp) / f"{args.world}-rtf{rtf:g}-{launch or 'node'}.mcap"
                start, stolen = time.perf_counter(), _steal()
                result = record_ros1(
                    scenario,
                    out,
                    args.package,
                    ros1_settings,
                    options=Ros1Options(launch=launch),
                    limits=MissionLimits(rtf=rtf),
                )
                wall = time.perf_counter() - start
                steal = steal_since(stolen)
                report = grade_file(out)
                rate_wall = rate_wall or wall
                twin = f", {wall / rate_wall:.2f}x the Rate run's wall" if launch in TWINS else ""
                ran = open_run(out).settings.record
                latency = ran.actuation_latency_ticks
                say(
                    f"{launch or pkg.name}, wall cap dt/{rtf:g}, latency {latency}, detection"
                    f" latency {ran.detection_latency_ticks}:"
                    f" {result.outcome}, "
                    f"{report.points:g}/{report.max_points:g} points, {result.sim_duration_s:.1f}"
                    f" s sim in {wall:.1f} s wall (incl. start-up): "
                    f"{result.sim_duration_s / wall:.2f}x real time{twin}{steal}; build + run +"
                    f" grade so far {time.perf_counter() - everything:.1f} s"
                )
                after = _python_rtf(scenario, Path(tmp) / f"python-{len(ros1) + 1}.mcap", "next")
                what = f"{launch or pkg.name} dt/{rtf:g}"
                ros1.append((what, result.sim_duration_s / wall, (python + after) / 2))
                python = after
        for what, rtf_reached, beside in ros1:
            say(
                f"  ROS 1 {what}: {rtf_reached:.2f}x vs Python {beside:.2f}x (the runs before "
                f"and after it): {rtf_reached / beside:.2f} of the Python mission's real-time "
                "factor"
            )


def say(text: str) -> None:
    """One result for people: wrapped at 100 columns, its later lines indented."""
    print(textwrap.fill(text, 100, subsequent_indent="    ", break_on_hyphens=False))


_COURSE: list[bool | None] = [None]
"""``--course-detection`` (None: the recorder's default)."""


def _python_rtf(scenario: Scenario, out: Path, when: str) -> float:
    """The built-in Python mission recorded on ``scenario``: its real-time factor, printed."""
    start, stolen = time.perf_counter(), _steal()
    course = _COURSE[0]
    settings = (
        RunSettings()
        if course is None
        else RunSettings(record=RecordSettings(course_detection=course))
    )
    result = python_record.record(scenario, out, settings)
    wall = time.perf_counter() - start
    steal = steal_since(stolen)
    report = grade_file(out)
    say(
        f"built-in Python mission ({when}): {result.outcome}, {report.points:g}/"
        f"{report.max_points:g} points, {result.sim_duration_s:.1f} s sim in {wall:.1f} s wall:"
        f" {result.sim_duration_s / wall:.2f}x real time{steal}"
    )
    return result.sim_duration_s / wall


def _steal() -> tuple[int, int]:
    """(steal, all) jiffies of the machine so far (``/proc/stat``): on a virtual machine, the
    time the host gave the CPUs to someone else."""
    fields = [int(x) for x in Path("/proc/stat").read_text().split("\n", 1)[0].split()[1:]]
    return (fields[7] if len(fields) > 7 else 0), sum(fields[:8])


def steal_since(before: tuple[int, int]) -> str:
    """`` (steal N%)``: the CPU time the host took since ``before`` (:func:`_steal`)."""
    now = _steal()
    total = now[1] - before[1]
    return f" (steal {100 * (now[0] - before[0]) / total:.0f}%)" if total > 0 else ""


def _children_cpu() -> float:
    import resource

    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


if __name__ == "__main__":
    main()
