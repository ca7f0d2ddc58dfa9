"""`usar batch` throughput: a small class graded with 1 and 2 local workers, and with Ray when
it is installed (printed, not asserted).

    python bench/bench_batch.py [--max-sim-time S] [--jobs N] [--ros1]

The class: examples/minimal_mission.py, a copy that raises when it reaches its first target and
a copy that hangs in its first timer callback (tick timeout 5 s), each on two one-room worlds
(tests/conftest.py's, and the same room with the robots' starts swapped): 6 runs. Each engine
grades the class into a fresh folder; the speed-up is the 1-worker wall time over the N-worker
one, and the logs' digests are compared across engines (they must be equal).

``--ros1``: the class is two copies of the course's ROS 1 package (examples/ros1/usar_course)
on the one-room world instead, graded with 1 and N local workers: each run has a CPU set of
its own (usar_replay/sandbox/cpu_sets.py), so N workers on N free CPUs use N CPUs. The build is
done once before the timings (its cache is shared), and the throughput ratio is printed.
"""

from __future__ import annotations

import argparse
import dataclasses
import hashlib
import shutil
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from conftest import one_room  # noqa: E402

from usar_replay.batch.driver import grade_class, plan_class  # noqa: E402
from usar_replay.batch.engines import make_engine  # noqa: E402
from usar_replay.core.limits import RunLimits  # noqa: E402
from usar_replay.core.settings import RecordSettings, RunSettings  # noqa: E402
from usar_replay.core.settings import to_toml as settings_to_toml  # noqa: E402
from usar_replay.log import bag  # noqa: E402
from usar_replay.world.scenario_toml import to_toml  # noqa: E402

MINIMAL = (ROOT / "examples" / "minimal_mission.py").read_text(encoding="utf-8")
ARRIVED = "    def arrived(self, _result: object) -> None:\n        self.spinning = True\n"
TIMER = "    def on_timer(self) -> None:\n"


def make_class(root: Path) -> tuple[Path, list[str]]:
    subs = root / "subs"
    subs.mkdir()
    (subs / "minimal.py").write_text(MINIMAL)
    (subs / "crash.py").write_text(
        MINIMAL.replace(ARRIVED, ARRIVED + "        raise RuntimeError\n")
    )
    (subs / "hang.py").write_text(MINIMAL.replace(TIMER, TIMER + "        while True: pass\n"))
    room = one_room()
    swapped = dataclasses.replace(
        room,
        name="one-room-swapped",
        explorer=dataclasses.replace(room.follower, name="explorer"),
        follower=dataclasses.replace(room.explorer, name="follower"),
    )
    worlds = []
    for w in (room, swapped):
        path = root / f"{w.name}.toml"
        path.write_text(to_toml(w))
        worlds.append(str(path))
    return subs, worlds


def digests(out: Path) -> dict[str, str]:
    result = {}
    for log in sorted(out.glob("*/*.mcap")):
        h = hashlib.sha256()
        for m in bag.BagReader(log).messages(decode_messages=False):
            h.update(m.topic.encode() + m.log_time_ns.to_bytes(8, "little") + m.data)
        result[f"{log.parent.name}/{log.name}"] = h.hexdigest()
    return result


def grade(subs: Path, worlds: list[str], out: Path, engine: str, jobs: int, sim: float) -> float:
    settings = RunSettings(record=RecordSettings(max_sim_time_s=sim))
    plan = plan_class(
        subs,
        out,
        scenarios=worlds,
        settings_toml=settings_to_toml(settings),
        limits=RunLimits(tick_timeout_s=5.0, cpu_s=1800),
    )
    t0 = time.perf_counter()
    grade_class(plan, make_engine(engine, jobs), quiet=True)
    return time.perf_counter() - t0


def make_ros1_class(root: Path) -> tuple[Path, list[str]]:
    subs = root / "subs"
    for team in ("a", "b"):
        shutil.copytree(ROOT / "examples" / "ros1" / "usar_course", subs / team)
    world = root / "room.toml"
    world.write_text(to_toml(one_room()))
    return subs, [str(world)]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--max-sim-time", type=float, default=30.0, help="sim seconds per run (30)")
    ap.add_argument("--jobs", type=int, default=2, help="workers of the parallel runs (2)")
    ap.add_argument("--ros1", action="store_true", help="a class of ROS 1 packages instead")
    args = ap.parse_args()
    if args.ros1:
        ros1(args.jobs, args.max_sim_time)
        return
    try:
        import ray  # noqa: F401

        engines = [("local", 1), ("local", args.jobs), ("ray", args.jobs)]
    except ImportError:
        engines = [("local", 1), ("local", args.jobs)]
        print("Ray is not installed: local engine only (pip install 'usar-replay[ray]')")
    with tempfile.TemporaryDirectory() as tmp:
        subs, worlds = make_class(Path(tmp))
        times: dict[tuple[str, int], float] = {}
        logs: dict[tuple[str, int], dict[str, str]] = {}
        for engine, jobs in engines:
            out = Path(tmp) / f"out-{engine}-{jobs}"
            times[(engine, jobs)] = grade(subs, worlds, out, engine, jobs, args.max_sim_time)
            logs[(engine, jobs)] = digests(out)
        base = times[("local", 1)]
        runs = 3 * len(worlds)
        for (engine, jobs), t in times.items():
            print(
                f"{engine:5} x{jobs}: {runs} runs ({args.max_sim_time:g} sim-s at most each) in "
                f"{t:6.1f} s wall, speed-up {base / t:4.2f}x over 1 local worker"
            )
        same = all(d == logs[("local", 1)] for d in logs.values())
        print(f"logs identical across engines: {'yes' if same else 'NO'}")


def ros1(jobs: int, sim: float) -> None:
    """Two copies of the course package, graded with 1 and ``jobs`` workers (docstring)."""
    with tempfile.TemporaryDirectory() as tmp:
        subs, worlds = make_ros1_class(Path(tmp))
        grade(subs, worlds, Path(tmp) / "warm", "local", 1, 1.0)  # the build, once
        times = {}
        logs = {}
        for n in (1, jobs):
            out = Path(tmp) / f"out-{n}"
            times[n] = grade(subs, worlds, out, "local", n, sim)
            logs[n] = digests(out)
        for n, t in times.items():
            print(
                f"ROS 1 local x{n}: 2 runs ({sim:g} sim-s at most each) in {t:6.1f} s wall, "
                f"{2 * 60 / t:5.2f} runs/min"
            )
        print(f"throughput x{jobs} / x1: {times[1] / times[jobs]:4.2f}")
        same = len({tuple(sorted(d.values())) for d in logs.values()}) == 1
        print(f"logs identical across job counts: {'yes' if same else 'NO'}")


if __name__ == "__main__":
    main()
