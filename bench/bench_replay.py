"""How fast replay and grading run on a recording (printed, never asserted).

* ``replay+grade``: ``usar replay --grade`` in-process, as sim seconds per wall second (the
  issue's target: about 50x real time on a 2-core machine for a 640x480@10 Hz course run), with
  the detector in the mission's thread (``workers=0``, what live recording does) and with the
  look-ahead detector threads (the default).
* ``grade``: ``usar grade`` alone (no replay), in seconds, in-process and as a command.

Usage::

    python bench/bench_replay.py [LOG.mcap] [--repeat N] [--profile]

The default log is ``recordings/course.mcap`` (record one with
``usar record``). ``--profile`` prints the top of a cProfile of one
default replay+grade, to see where the time goes.
"""

from __future__ import annotations

import argparse
import cProfile
import io
import os
import pstats
import resource
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from usar_replay import bag
from usar_replay.grade import GRADE_TOPICS, REQUIRED_TOPICS, Grader, grade_file
from usar_replay.replay import ReplayReport, default_workers, load_scenario, replay

DEFAULT_LOG = Path("recordings/course.mcap")


@dataclass(frozen=True, slots=True)
class Timing:
    """One run: wall seconds, CPU seconds of the whole process and of the main thread."""

    wall_s: float
    cpu_s: float
    main_cpu_s: float

    def two_core_floor_s(self, workers: int) -> float:
        """The least wall time this CPU work needs on two idle cores: the main thread and the
        detector threads overlap, so it is bounded by the main thread, by the detector work
        spread over its threads (at most two at once), and by half the total."""
        if workers == 0:
            return self.cpu_s
        detect_s = self.cpu_s - self.main_cpu_s
        return max(self.main_cpu_s, detect_s / min(workers, 2), self.cpu_s / 2)


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def replay_and_grade(path: Path, workers: int | None) -> tuple[Timing, ReplayReport, float]:
    """(timing, replay report, points) of one ``usar replay --grade``."""
    cpu0, main0 = _cpu(), time.thread_time()
    t = time.perf_counter()
    grader = Grader(load_scenario(bag.BagReader(path)))
    report = replay(
        path,
        grade_sink=grader.feed,
        grade_topics=GRADE_TOPICS,
        required_topics=REQUIRED_TOPICS,
        workers=workers,
    )
    points = grader.report(str(path)).points
    timing = Timing(time.perf_counter() - t, _cpu() - cpu0, time.thread_time() - main0)
    return timing, report, points


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("log", nargs="?", type=Path, default=DEFAULT_LOG)
    parser.add_argument("--repeat", type=int, default=1, help="best of N runs")
    parser.add_argument(
        "--workers",
        default="0,default",
        help="detector thread counts to compare, e.g. 0,1,2,default (0: in the mission's thread)",
    )
    parser.add_argument("--profile", action="store_true", help="cProfile one default run")
    args = parser.parse_args()
    path: Path = args.log
    if not path.exists():
        sys.exit(f"{path}: no such log; record one with `usar record --out {path}`")
    reader = bag.BagReader(path)
    sim_s = (reader.end_ns - reader.start_ns) / 1e9
    frames = reader.topics.get("/explorer/camera/rgb/image_raw/compressed")
    print(
        f"log {path}: {sim_s:.1f} sim s, {reader.message_count} messages, "
        f"{frames.count if frames else 0} frames, {reader.size_bytes / 1e6:.1f} MB; "
        f"{os.cpu_count()} CPUs, default detector threads {default_workers()}"
    )
    counts = [None if w.strip() == "default" else int(w) for w in args.workers.split(",")]
    for workers in counts:
        best: Timing | None = None
        for _ in range(max(args.repeat, 1)):
            timing, report, points = replay_and_grade(path, workers)
            if best is None or timing.wall_s < best.wall_s:
                best = timing
        assert best is not None
        n = default_workers() if workers is None else workers
        label = "in the mission's thread" if n == 0 else f"{n} look-ahead thread(s)"
        floor = best.two_core_floor_s(n)
        print(
            f"replay+grade, detector {label:<24}: {best.wall_s:6.2f} s wall = "
            f"{sim_s / best.wall_s:5.1f}x real time; CPU {best.cpu_s:5.1f} s "
            f"(main thread {best.main_cpu_s:4.1f} s) -> on 2 idle cores >= {floor:5.2f} s = "
            f"{sim_s / floor:5.1f}x"
        )
        print(
            f"    identical={report.identical} points={points:g} frames detected "
            f"{report.frames_detected}, reused {report.frames_reused}, "
            f"peak outputs held {report.peak_pending}"
        )
    best_grade = min(_timed(lambda: grade_file(path)) for _ in range(max(args.repeat, 1)))
    print(f"usar grade (in-process, no replay)           : {best_grade:6.2f} s")
    t = time.perf_counter()
    subprocess.run(
        [sys.executable, "-m", "usar_replay.cli", "grade", str(path)],
        check=False,
        capture_output=True,
    )
    print(f"usar grade (command, with interpreter start) : {time.perf_counter() - t:6.2f} s")
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak resident memory of this process: {peak_mb:.0f} MB")
    if args.profile:
        prof = cProfile.Profile()
        prof.enable()
        replay_and_grade(path, None)
        prof.disable()
        out = io.StringIO()
        pstats.Stats(prof, stream=out).sort_stats("tottime").print_stats(15)
        print(out.getvalue())


def _timed(fn: Callable[[], object]) -> float:
    t = time.perf_counter()
    fn()
    return time.perf_counter() - t


if __name__ == "__main__":
    main()
