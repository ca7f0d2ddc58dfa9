"""What the kernel sandbox (sandbox/kernel_sandbox.py) costs: per run (starting the mission
process) and per tick (the process boundary, and a short one-room recording), with and without
bwrap. Printed, never asserted.

    python bench/bench_sandbox.py [--runs 5] [--ticks 1000] [--sim-s 10]

Start-up is the wall time from starting the mission process to its first "ready" (Python, numpy,
OpenCV and the node API imported, ``main()`` run) plus closing it; the boundary is µs per tick
through an idle mission (CDR both ways + IPC, a 25 kB image per tick); the recording is the
built-in mission on the one-room world, wall time and the recorder's CPU time per control tick.
Runs alternate bare / sandboxed so that a busy machine hits both alike; medians are shown.
"""

from __future__ import annotations

import argparse
import dataclasses
import resource
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))

from usar_replay.core import cdr, contract, msgs  # noqa: E402
from usar_replay.process.mission_process import MissionLimits, MissionProcess  # noqa: E402
from usar_replay.process.mission_target import resolve_target  # noqa: E402
from usar_replay.sandbox.kernel_sandbox import bwrap_available  # noqa: E402

MODES = {"bare": "off", "bwrap": "required"}


def _tick_wire(t: int, image_bytes: int) -> list[tuple[str, str, bytes]]:
    image = msgs.CompressedImage(
        header=msgs.Header(stamp=msgs.Time.from_ns(t), frame_id=contract.OPTICAL_FRAME),
        format="png",
        data=bytes(image_bytes),
    )
    items: list[tuple[str, msgs.Message]] = [(contract.IMAGE, image)]
    items += [(contract.odom(r), msgs.Odometry()) for r in contract.ROBOTS]
    return [(topic, m.__msgtype__, cdr.encode(m)) for topic, m in items]


def _process(mode: str) -> MissionProcess:
    return MissionProcess(
        resolve_target(str(ROOT / "bench" / "_idle_mission.py")),
        {},
        sim_topics=contract.SIM_TOPICS,
        sim_frames=contract.sim_frames(),
        limits=MissionLimits(kernel_sandbox=mode),
    )


def startup_s(mode: str) -> tuple[float, float]:
    """(start to ready, close) in seconds."""
    t0 = time.perf_counter()
    proc = _process(mode)
    t1 = time.perf_counter()
    proc.close()
    return t1 - t0, time.perf_counter() - t1


def boundary_us(mode: str, ticks: int) -> float:
    wire = _tick_wire(1_000_000_000, 25_000)
    with _process(mode) as proc:
        t0 = time.perf_counter()
        for i in range(ticks):
            proc.tick(1_000_000_000 + i * 50_000_000, wire)
        return (time.perf_counter() - t0) / ticks * 1e6


def _cpu() -> float:
    """This process's CPU time (the recorder's): a sandboxed mission's is not visible here,
    as bwrap's monitor exits without reaping the sandbox's init, so its CPU never reaches
    RUSAGE_CHILDREN; only the recorder's side is compared."""
    own = resource.getrusage(resource.RUSAGE_SELF)
    return own.ru_utime + own.ru_stime


def recording_ms_per_tick(mode: str, sim_s: float) -> tuple[float, float]:
    from conftest import one_room

    from usar_replay.core.settings import RunSettings
    from usar_replay.pipeline.record import record

    base = RunSettings()
    settings = RunSettings(record=dataclasses.replace(base.record, max_sim_time_s=sim_s))
    ticks = sim_s * base.record.control_hz
    with tempfile.TemporaryDirectory() as tmp:
        c0, t0 = _cpu(), time.perf_counter()
        limits = MissionLimits(kernel_sandbox=mode)
        record(one_room(), Path(tmp) / "room.mcap", settings, limits=limits)
        wall, cpu = time.perf_counter() - t0, _cpu() - c0
    return wall / ticks * 1e3, cpu / ticks * 1e3


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5, help="start-ups per mode")
    ap.add_argument("--ticks", type=int, default=1000, help="boundary ticks per mode")
    ap.add_argument("--sim-s", type=float, default=10.0, help="sim seconds of each recording")
    args = ap.parse_args()
    ok, why = bwrap_available()
    if not ok:
        sys.exit(f"bench_sandbox: {why}; apt-get install bubblewrap")
    starts: dict[str, list[tuple[float, float]]] = {m: [] for m in MODES}
    for _ in range(args.runs):
        for mode, setting in MODES.items():
            starts[mode].append(startup_s(setting))
    print(f"mission process start-up to ready, and close (median of {args.runs}):")
    for mode in MODES:
        up = statistics.median(s for s, _ in starts[mode]) * 1e3
        down = statistics.median(c for _, c in starts[mode]) * 1e3
        print(f"  {mode:6s} {up:8.1f} ms start  {down:8.1f} ms close")
    print(f"process boundary, idle mission, 25 kB image per tick ({args.ticks} ticks):")
    for mode, setting in MODES.items():
        print(f"  {mode:6s} {boundary_us(setting, args.ticks):8.1f} µs/tick")
    print(f"one-room recording, built-in mission, {args.sim_s:g} sim-s:")
    recording_ms_per_tick("off", 1.0)  # warm-up: the first recording loads pybullet and EGL
    for mode, setting in MODES.items():
        wall, cpu = recording_ms_per_tick(setting, args.sim_s)
        print(f"  {mode:6s} {wall:8.2f} ms wall/tick  {cpu:8.2f} ms recorder CPU/tick")


if __name__ == "__main__":
    main()
