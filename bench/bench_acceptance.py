"""Acceptance of the whole mission: the course world and N seeded variants, recorded and graded.

    python bench/bench_acceptance.py [--seeds 10] [--jobs 1] [--out recordings/acceptance]

For each world it records the mission with the default settings (640x480 @ 10 Hz), grades the
log, and prints one row: mission done, sim duration, markers found, their worst map error
against the truth, rubric points, wall time and real-time factor. Numbers are printed, never
asserted: this is the measurement behind the README's acceptance table.
"""

from __future__ import annotations

import argparse
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from usar_replay.core.settings import RunSettings
from usar_replay.grading.grade import grade_file
from usar_replay.pipeline.record import record
from usar_replay.world.scenario import course_world
from usar_replay.world.variants import make_variant


def run(seed: int | None, out_dir: Path) -> str:
    scn = course_world() if seed is None else make_variant(course_world(), seed)
    name = "course" if seed is None else f"seed{seed}"
    path = out_dir / f"{name}.mcap"
    t0 = time.perf_counter()
    result = record(scn, path, RunSettings())
    wall = time.perf_counter() - t0
    grade = grade_file(path)
    worst = max(result.marker_errors_m.values(), default=float("nan"))
    failed = ",".join(c.id for c in grade.checks if not c.passed) or "-"
    return (
        f"{name:<8} {'yes' if result.mission_done else 'NO':<5} {result.sim_duration_s:7.1f} "
        f"{len(result.markers_found)}/{len(scn.markers)}   {worst * 100:6.2f} "
        f"{grade.points:5.1f}/{grade.max_points:g} {wall:7.1f} {result.real_time_factor:5.2f} "
        f"{result.size_bytes / 1e6:6.1f}  {failed}"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10, help="how many seeded variants (0..N-1)")
    ap.add_argument("--jobs", type=int, default=1, help="worlds recorded in parallel")
    ap.add_argument("--out", default="recordings/acceptance", help="where the logs go")
    ap.add_argument("--no-course", action="store_true", help="skip the course world")
    ap.add_argument("--only", metavar="S,S,...", help="these seeds instead of 0..N-1")
    args = ap.parse_args()
    out_dir = Path(args.out)
    out_dir.mkdir(parents=True, exist_ok=True)
    seeds = [int(x) for x in args.only.split(",")] if args.only else list(range(args.seeds))
    worlds: list[int | None] = ([] if args.no_course else [None]) + seeds
    print("world    done   sim s  found  worst cm  points   wall s   RTF     MB  failed lines")
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        futures = [pool.submit(run, w, out_dir) for w in worlds]
        for w, fut in zip(worlds, futures, strict=True):
            try:
                print(fut.result(), flush=True)
            except Exception as err:  # noqa: BLE001 - one broken world must not hide the others
                print(f"{'course' if w is None else f'seed{w}':<8} ERROR {err!r}", flush=True)


if __name__ == "__main__":
    main()
