"""How fast replay and grading run on a recording (printed, never asserted).

* ``replay+grade``: ``usar replay --grade`` in-process, as sim seconds per wall second, with the
  mission in its own process and ``--window`` ticks in flight (1: no pipelining, as a closed
  loop would be). The issue's targets: 80x real time (50x the floor), peak memory < 300 MB.
* ``grade``: ``usar grade`` alone (no replay), in-process and as the command (interpreter start
  and imports included), as CPU and wall seconds and as a fraction of the sim time (the
  target: under 1/400). CPU time is the figure to compare on a shared machine.

Usage::

    python bench/bench_replay.py [LOG.mcap] [--repeat N] [--windows 1,8] [--grade-only]

The default log is ``recordings/course.mcap`` (record one with ``usar record``).
"""

from __future__ import annotations

import argparse
import resource
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

from usar_replay.grading.grade import grade_file
from usar_replay.grading.usar import GRADE_TOPICS, REQUIRED_TOPICS, Grader
from usar_replay.log.run import open_run
from usar_replay.pipeline.replay import ReplayReport, replay

DEFAULT_LOG = Path("recordings/course.mcap")


def _cpu() -> tuple[float, float]:
    """CPU seconds so far of (this process, its finished children: the mission processes)."""
    r = resource.getrusage(resource.RUSAGE_SELF)
    c = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime, c.ru_utime + c.ru_stime


def replay_and_grade(
    path: Path, window: int
) -> tuple[float, tuple[float, float], ReplayReport, float]:
    """(wall s, CPU s of (usar, the mission process), report, points) of one replay --grade.

    On 2 cores the two processes run at once, so the wall time is about the larger of the two
    CPU times when the machine is otherwise idle: the CPU times say which side to speed up.
    """
    own0, child0 = _cpu()
    t = time.perf_counter()
    run = open_run(path)
    grader = Grader(run.require_scenario())
    report = replay(
        run,
        grade_sink=grader.feed,
        grade_topics=GRADE_TOPICS,
        required_topics=REQUIRED_TOPICS,
        window=window,
    )
    points = grader.report(str(path)).points
    wall = time.perf_counter() - t
    own1, child1 = _cpu()
    return wall, (own1 - own0, child1 - child0), report, points


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("log", nargs="?", type=Path, default=DEFAULT_LOG)
    parser.add_argument("--repeat", type=int, default=1, help="best of N runs")
    parser.add_argument("--windows", default="1,8", help="ticks in flight to compare")
    parser.add_argument("--grade-only", action="store_true", help="skip replay+grade")
    args = parser.parse_args()
    path: Path = args.log
    if not path.exists():
        sys.exit(f"{path}: no such log; record one with `usar record --out {path}`")
    run = open_run(path)
    sim_s = run.duration_s
    frames = run.topics.get("/explorer/camera/rgb/image_raw/compressed")
    print(
        f"log {path}: {sim_s:.1f} sim s, {run.reader.message_count} messages, "
        f"{frames.count if frames else 0} frames, {run.reader.size_bytes / 1e6:.1f} MB"
    )
    for window in () if args.grade_only else (int(w) for w in args.windows.split(",")):
        best = min(
            (replay_and_grade(path, window) for _ in range(max(args.repeat, 1))),
            key=lambda r: r[0],
        )
        wall, cpu, report, points = best
        print(
            f"replay+grade, {window} tick(s) in flight: {wall:6.2f} s wall = "
            f"{sim_s / wall:5.1f}x real time; CPU {cpu[0]:5.1f} s usar + {cpu[1]:5.1f} s mission "
            f"= {sim_s / max(cpu):5.1f}x real time on two idle cores; "
            f"identical={report.identical} points={points:g}"
        )
    repeat = max(args.repeat, 1)
    cpu, wall = min(_timed(lambda: grade_file(path)) for _ in range(repeat))
    print(
        f"usar grade (in-process, no replay): CPU {cpu:5.2f} s = 1/{sim_s / cpu:.0f} of the sim "
        f"time; wall {wall:5.2f} s"
    )
    cpu, wall = min(_timed_command(path) for _ in range(repeat))
    print(
        f"usar grade (command, with interpreter start): CPU {cpu:5.2f} s = 1/{sim_s / cpu:.0f} "
        f"of the sim time; wall {wall:5.2f} s = 1/{sim_s / wall:.0f}"
    )
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    child_mb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    print(f"peak resident memory: {peak_mb:.0f} MB (usar), {child_mb:.0f} MB (mission process)")


def _timed(fn: Callable[[], object]) -> tuple[float, float]:
    """(CPU s, wall s) of one call."""
    c, t = time.process_time(), time.perf_counter()
    fn()
    return time.process_time() - c, time.perf_counter() - t


def _timed_command(path: Path) -> tuple[float, float]:
    """(CPU s, wall s) of ``usar grade PATH`` in a fresh interpreter."""
    c, t = _children_cpu(), time.perf_counter()
    subprocess.run(
        [sys.executable, "-m", "usar_replay.cli", "grade", str(path)],
        check=False,
        capture_output=True,
    )
    return _children_cpu() - c, time.perf_counter() - t


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


if __name__ == "__main__":
    main()
