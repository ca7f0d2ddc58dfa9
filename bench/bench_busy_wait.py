"""Busy waits with no pausing point against the same logic with ``ros::Rate`` (issue 43, item 5).

    python bench/bench_busy_wait.py [--rounds 3] [--shapes rate silent late ok]

Builds the test package of ``tests/busy_wait_package.py`` once (a node that sends the explorer
two move_base goals and waits for each: ``silent``, ``while (getState() != SUCCEEDED) {}`` with
no call at all; ``late``, the same after a second of sim time asleep, so that its thread is
real-time when it starts to spin; ``ok``, ``while (ros::ok()) { if (SUCCEEDED) {...; sleep} }``;
``rate``, the same logic in a ``ros::Rate(20)`` loop) and records each shape on the one-room
world, the shapes interleaved round by round (a shared machine's speed drifts by 10-40% within
minutes: back-to-back runs compare best). Prints per run the outcome, sim time, the wall time
of its ticks (the start-up before the first tick is left out: the same for every shape, and
6-64 s on this shared machine for the same run) and of the whole run, the log's sha256 (the
same for every recording of a shape) and the ticks' wall time as a ratio to the ``rate`` run
of the same round (issue 43 wants the busy shapes within 2x), and each shape's
median ratio at the end, with the machine's CPU steal meanwhile. Nothing is asserted; the
numbers go into docs/ros1.md ("Busy waits with no call at all").
"""

from __future__ import annotations

import argparse
import hashlib
import statistics
import sys
import tempfile
import time
from pathlib import Path

from usar_replay.core.settings import RunSettings
from usar_replay.log.run import open_run
from usar_replay.ros1.process import Ros1Options
from usar_replay.ros1.record import record_ros1

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
import busy_wait_package
from conftest import one_room


def _steal() -> tuple[int, int]:
    """(steal, total) jiffies of the machine so far (``/proc/stat``)."""
    fields = [int(v) for v in Path("/proc/stat").read_text().split("\n", 1)[0].split()[1:]]
    return fields[7] if len(fields) > 7 else 0, sum(fields)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--shapes", nargs="+", default=list(busy_wait_package.SHAPES))
    args = ap.parse_args()
    shapes = ["rate", *[s for s in args.shapes if s != "rate"]]
    ratios: dict[str, list[float]] = {s: [] for s in shapes}
    with tempfile.TemporaryDirectory(prefix="usar-bench-busy-") as tmp:
        pkg = busy_wait_package.write(Path(tmp) / busy_wait_package.NAME)
        t = time.perf_counter()
        _record(pkg, Path(tmp) / "warm.mcap", "rate")  # the build, once (cached after)
        print(f"build + first run: {time.perf_counter() - t:.1f} s", flush=True)
        steal = _steal()
        for round_ in range(1, args.rounds + 1):
            rate_wall = 0.0
            for shape in shapes:
                out = Path(tmp) / f"{shape}-{round_}.mcap"
                wall, line = _record(pkg, out, shape)
                if shape == "rate":
                    rate_wall = wall
                ratio = wall / rate_wall if rate_wall else float("nan")
                ratios[shape].append(ratio)
                print(f"round {round_} {shape:6s} {line}  {ratio:.2f}x the rate run", flush=True)
        s, total = (a - b for a, b in zip(_steal(), steal, strict=True))
        print(f"steal meanwhile: {100.0 * s / max(total, 1):.1f}% of the CPUs")
        for shape in shapes[1:]:
            print(f"{shape}: median {statistics.median(ratios[shape]):.2f}x the rate run's wall")


def _record(pkg: Path, out: Path, shape: str) -> tuple[float, str]:
    """One recording: the wall time of its ticks (from the first tick's progress to the end:
    the start-up before it, the master, roslaunch and the imports, took 6-64 s on this shared
    machine for the same run, and is the same for every shape) and a line about it."""
    first: list[float] = []
    t = time.perf_counter()
    result = record_ros1(
        one_room(),
        out,
        pkg,
        RunSettings(),
        progress=lambda _p: first.append(time.perf_counter()) if not first else None,
        options=Ros1Options(launch=busy_wait_package.launch_file(shape)),
    )
    end = time.perf_counter()
    whole = end - t
    wall = end - (first[0] if first else t)
    run = open_run(out)
    sim = run.duration_s
    digest = hashlib.sha256(out.read_bytes()).hexdigest()[:12]
    return wall, (
        f"{result.outcome:6s} sim {sim:5.1f} s  ticks {wall:5.1f} s (run {whole:5.1f} s)  "
        f"{result.pacing}  sha256 {digest}"
    )


if __name__ == "__main__":
    main()
