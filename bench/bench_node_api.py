"""What the node API costs: the executor per tick, the process boundary per tick, and a whole
recording and replay against the code before the node API (printed, never asserted).

    python bench/bench_node_api.py                       # executor + boundary micro-benchmarks
    python bench/bench_node_api.py --baseline-rev 3ca31dc   # + one-room record/replay vs then

The baseline is checked out into a temporary git worktree and run in a subprocess with the same
Python; both recordings run one after the other on the same world, and the ratio of their times
(wall and CPU, children included) is the node API's share. CPU time is the steadier number on a
busy machine.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))

from usar_replay.core import cdr, contract, msgs  # noqa: E402
from usar_replay.node.executor import Executor, PublishPolicy  # noqa: E402
from usar_replay.node.node import Node  # noqa: E402


def _tick(t: int, image_bytes: int) -> list[tuple[str, msgs.Message]]:
    tf = msgs.TFMessage(
        transforms=tuple(
            msgs.TransformStamped(
                header=msgs.Header(stamp=msgs.Time.from_ns(t), frame_id=contract.odom_frame(r)),
                child_frame_id=contract.base_frame(r),
            )
            for r in contract.ROBOTS
        )
    )
    image = msgs.CompressedImage(
        header=msgs.Header(stamp=msgs.Time.from_ns(t), frame_id=contract.OPTICAL_FRAME),
        format="png",
        data=bytes(image_bytes),
    )
    odoms = [(contract.odom(r), msgs.Odometry()) for r in contract.ROBOTS]
    return [(contract.TF, tf), (contract.IMAGE, image), *odoms]


def bench_executor(n: int = 20_000) -> float:
    """µs per tick for the executor alone: 4 inputs to 6 subscriptions, 2 publishes."""
    ex = Executor({}, PublishPolicy(contract.SIM_TOPICS, contract.sim_frames()))
    with ex.activate():
        node = Node("bench")
        pub = node.create_publisher(msgs.Twist, contract.cmd_vel("explorer"))
        for topic in (contract.TF, contract.IMAGE, *(contract.odom(r) for r in contract.ROBOTS)):
            node.create_subscription(msgs.Message, topic, lambda m: None)
        node.create_subscription(
            msgs.Odometry, contract.odom("explorer"), lambda m: pub.publish(msgs.Twist())
        )
        node.create_timer(0.05, lambda: pub.publish(msgs.Twist()))
        ticks = [_tick(1_000_000_000 + i * 50_000_000, 100) for i in range(100)]
        t0 = time.perf_counter()
        for i in range(n):
            ex.tick(1_000_000_000 + i * 50_000_000, ticks[i % 100])
        return (time.perf_counter() - t0) / n * 1e6


def bench_boundary(n: int = 2_000, image_bytes: int = 25_000) -> float:
    """µs per tick through a mission process whose nodes do nothing (CDR both ways + IPC)."""
    from usar_replay.process.mission_process import MissionProcess
    from usar_replay.process.mission_target import resolve_target

    target = resolve_target(str(ROOT / "bench" / "_idle_mission.py"))
    wire = [(t, m.__msgtype__, cdr.encode(m)) for t, m in _tick(1_000_000_000, image_bytes)]
    with MissionProcess(
        target, {}, sim_topics=contract.SIM_TOPICS, sim_frames=contract.sim_frames()
    ) as proc:
        t0 = time.perf_counter()
        for i in range(n):
            proc.tick(1_000_000_000 + i * 50_000_000, wire)
        return (time.perf_counter() - t0) / n * 1e6


_RECORD = """
import sys, time, resource
sys.path.insert(0, {tests!r})
from conftest import one_room
from usar_replay.pipeline.record import record
try:
    from usar_replay.core.settings import RunSettings as S
except ImportError:
    from usar_replay.pipeline.record import RecordSettings as S
from usar_replay.pipeline.replay import replay
if __name__ == "__main__":
    import dataclasses as dc
    room = one_room()
    room = dc.replace(room, camera=dc.replace(room.camera, encoding="png"))  # the same codec
    t = time.perf_counter(); r = record(room, {out!r}, S()); w = time.perf_counter() - t
    t = time.perf_counter(); rep = replay({out!r}); w2 = time.perf_counter() - t
    ru = resource.getrusage(resource.RUSAGE_SELF)
    rc = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = ru.ru_utime + ru.ru_stime + rc.ru_utime + rc.ru_stime
    print(r.sim_duration_s, w, w2, cpu, rep.identical)
"""


def run_tree(tree: Path, out: Path) -> tuple[float, float, float, float]:
    code = _RECORD.format(tests=str(tree / "tests"), out=str(out))
    env = dict(os.environ, PYTHONPATH=str(tree))
    res = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    sim, wall, wall_replay, cpu, same = res.stdout.split()
    assert same == "True", res.stdout
    return float(sim), float(wall), float(wall_replay), float(cpu)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline-rev", help="git revision before the node API (e.g. 3ca31dc)")
    args = ap.parse_args()
    print(f"executor: {bench_executor():.1f} us per tick (4 inputs, 6 subscriptions, 2 publishes)")
    print(f"process boundary: {bench_boundary():.0f} us per tick (a 25 kB frame, CDR + IPC)")
    if not args.baseline_rev:
        return
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp) / "base"
        subprocess.run(
            ["git", "-C", str(ROOT), "worktree", "add", "--detach", str(base), args.baseline_rev],
            check=True,
            capture_output=True,
        )
        try:
            rows = [
                ("before the node API", run_tree(base, Path(tmp) / "a.mcap")),
                ("node API (now)", run_tree(ROOT, Path(tmp) / "b.mcap")),
            ]
        finally:
            subprocess.run(
                ["git", "-C", str(ROOT), "worktree", "remove", "--force", str(base)], check=False
            )
    print(
        f"{'one-room world':<22} {'sim s':>6} {'record s':>9} {'x real':>7} {'replay s':>9} "
        f"{'x real':>7} {'CPU s':>7}"
    )
    for name, (sim, wall, wall_rep, cpu) in rows:
        print(
            f"{name:<22} {sim:6.1f} {wall:9.1f} {sim / wall:7.2f} {wall_rep:9.1f} "
            f"{sim / wall_rep:7.1f} {cpu:7.1f}"
        )
    (_, a), (_, b) = rows
    print(
        f"node API / before: record {b[1] / a[1]:.2f}x wall, replay {b[2] / a[2]:.2f}x wall, "
        f"{b[3] / a[3]:.2f}x CPU"
    )
    _ = resource  # imported for the subprocess's code shape


if __name__ == "__main__":
    main()
