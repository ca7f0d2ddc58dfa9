"""`usar record --ros1`: build time and the real-time factor a C++ course node sustains.

    python bench/bench_ros1.py [--world room|course] [--rtf 0.5] [--package DIR]

Builds the package once into an empty build cache (catkin_make: the build time), then records
it on the world with each ``--rtf`` wall cap (the slowest pace, a safety net: the graph itself
paces the clock, docs/ros1.md), reusing that build, and prints per run: the outcome, the
rubric's points, sim time, wall time and the real-time factor reached (sim / wall), and the
whole build + run + grade time. Nothing is asserted; the numbers go into docs/ros1.md.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

from usar_replay.core.settings import RunSettings
from usar_replay.grading.grade import grade_file
from usar_replay.node.mission_process import MissionLimits, uses_kernel_sandbox
from usar_replay.ros1 import build as build_mod
from usar_replay.ros1.process import Ros1Options
from usar_replay.ros1.record import record_ros1
from usar_replay.world.scenario import course_world

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from conftest import one_room

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "ros1" / "usar_course"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--world", choices=["room", "course"], default="room")
    ap.add_argument("--rtf", type=float, nargs="+", default=[0.5])
    ap.add_argument("--package", default=str(EXAMPLE))
    args = ap.parse_args()
    scenario = one_room() if args.world == "room" else course_world()
    with tempfile.TemporaryDirectory(prefix="bench-ros1-") as tmp:
        os.environ["XDG_CACHE_HOME"] = tmp  # a cold build, then the runs reuse it
        pkg = build_mod.find_package(args.package)
        t0 = everything = time.perf_counter()
        cpu0 = _children_cpu()
        # built as the recording will want it (at the sandbox's fixed paths when there is one)
        build_mod.cached_build(pkg, fixed=uses_kernel_sandbox(MissionLimits()))
        print(
            f"build: {time.perf_counter() - t0:.1f} s wall, {_children_cpu() - cpu0:.1f} s CPU"
            f" (catkin_make -j2, {pkg.name} + fiducial_msgs)"
        )
        for rtf in args.rtf:
            out = Path(tmp) / f"{args.world}-rtf{rtf:g}.mcap"
            start = time.perf_counter()
            result = record_ros1(
                scenario, out, args.package, RunSettings(), options=Ros1Options(rtf=rtf)
            )
            wall = time.perf_counter() - start
            report = grade_file(out)
            print(
                f"wall cap dt/{rtf:g}: {result.outcome}, {report.points:g}/{report.max_points:g} "
                f"points, {result.sim_duration_s:.1f} s sim in {wall:.1f} s wall "
                f"(incl. start-up): {result.sim_duration_s / wall:.2f}x real time; build + run + "
                f"grade so far {time.perf_counter() - everything:.1f} s"
            )


def _children_cpu() -> float:
    import resource

    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


if __name__ == "__main__":
    main()
