"""What a tick costs once a team's graph has nothing left to do (issue 51, point 7).

    python bench/bench_idle.py [--shapes done spin rate poll] [--max-sim-time 40] [--rounds 1]

Builds the test package of ``tests/idle_package.py`` once (a node with a tf2 listener and a
``/fiducial_transforms`` subscriber that sends the explorer one goal, logs ``mission over at
T``, then ends (``done``) or idles: ``ros::spin()`` with a 10 Hz timer (``spin``), a 10 Hz
``ros::Rate`` loop (``rate``), a busy ``spinOnce`` poll (``poll``), a loop with no call at all
(``silent``)) and records each shape on the one-room world (``--world course``: the course
world) to ``--max-sim-time`` (default 40 s of sim time; ``done`` ends by itself
some 5 s in), the shapes interleaved round by round. Per run: the outcome, the sim time, the
mean wall milliseconds of a control tick (20 Hz) while the mission ran (from the first tick to
the ``mission over`` line) and after it (the idle ticks; the first second after the line left
out), the log's sha256 and the pacing summary. The issue wants the idle figure no more than the
mission's. Nothing is asserted; the numbers go into docs/ros1.md ("Idle ticks").
"""

from __future__ import annotations

import argparse
import hashlib
import os
import sys
import tempfile
import time
from pathlib import Path

from usar_replay.core.settings import RecordSettings, RunSettings
from usar_replay.pipeline.record import Progress
from usar_replay.ros1.process import Ros1Options
from usar_replay.ros1.record import record_ros1
from usar_replay.world.scenario import Scenario, course_world

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
import idle_package
from conftest import one_room

SETTLE_S = 1.0
"""Sim seconds after the ``mission over`` line before idle ticks are counted."""


class Ticks:
    """The wall time of each control tick, from the recorder's progress callback."""

    def __init__(self) -> None:
        self.marks: list[tuple[float, float]] = []
        """(sim s, wall s) after each tick."""
        self.over_s: float | None = None

    def __call__(self, p: Progress) -> None:
        self.marks.append((p.sim_time_s, time.perf_counter()))
        lines = [p.last_log, *(line for _, line in p.node_lines)]
        if self.over_s is None and any(idle_package.OVER in line for line in lines):
            self.over_s = p.sim_time_s

    def per_tick_ms(self, lo: float, hi: float) -> float:
        """Mean wall ms of the ticks whose sim time is in (lo, hi]."""
        inside = [i for i, (s, _) in enumerate(self.marks) if lo < s <= hi and i > 0]
        if not inside:
            return float("nan")
        wall = sum(self.marks[i][1] - self.marks[i - 1][1] for i in inside)
        return 1000.0 * wall / len(inside)


def record(world: Scenario, pkg: Path, out: Path, shape: str, max_sim: float) -> str:
    """One recording and its line."""
    ticks = Ticks()
    t = time.perf_counter()
    result = record_ros1(
        world,
        out,
        pkg,
        RunSettings(record=RecordSettings(max_sim_time_s=max_sim)),
        progress=ticks,
        options=Ros1Options(launch=idle_package.launch_file(shape)),
    )
    whole = time.perf_counter() - t
    over = ticks.over_s if ticks.over_s is not None else float("inf")
    mission = ticks.per_tick_ms(0.0, over)
    idle = ticks.per_tick_ms(over + SETTLE_S, float("inf"))
    digest = hashlib.sha256(out.read_bytes()).hexdigest()[:12]
    return (
        f"{shape:5s} {result.outcome:12s} sim {result.sim_duration_s:5.1f} s  over {over:5.1f} s"
        f"  mission {mission:5.1f} ms/tick  idle {idle:5.1f} ms/tick  run {whole:5.1f} s"
        f"  sha256 {digest}  {result.pacing}"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shapes", nargs="+", default=list(idle_package.SHAPES))
    ap.add_argument("--max-sim-time", type=float, default=40.0)
    ap.add_argument("--rounds", type=int, default=1)
    ap.add_argument("--world", choices=("room", "course"), default="room")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="usar-bench-idle-") as tmp:
        pkg = idle_package.write(Path(tmp) / idle_package.NAME)
        t = time.perf_counter()
        world = course_world() if args.world == "course" else one_room()
        record(world, pkg, Path(tmp) / "warm.mcap", "done", args.max_sim_time)  # the build, once
        print(f"build + first run: {time.perf_counter() - t:.1f} s", flush=True)
        for round_ in range(1, args.rounds + 1):
            for shape in args.shapes:
                load = os.getloadavg()[0]
                out = Path(tmp) / f"{shape}-{round_}.mcap"
                line = record(world, pkg, out, shape, args.max_sim_time)
                print(f"round {round_} load {load:4.1f}  {line}", flush=True)


if __name__ == "__main__":
    main()
