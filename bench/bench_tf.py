"""Microseconds per tf lookup on a 5-link chain with interpolation (printed, not asserted).

    python bench/bench_tf.py

The real tf2 (C++ behind rclpy) answers such a lookup in about 17 us on these machines.
"""

from __future__ import annotations

import itertools
import math
import time

from usar_replay.core import msgs
from usar_replay.core.tf_tree import BufferCore

S = 1_000_000_000


def _tf(parent: str, child: str, stamp: int, k: float) -> msgs.TransformStamped:
    return msgs.TransformStamped(
        header=msgs.Header(stamp=msgs.Time.from_ns(stamp), frame_id=parent),
        child_frame_id=child,
        transform=msgs.Transform(
            translation=msgs.Vector3(x=k, y=0.5 * k, z=0.1),
            rotation=msgs.Quaternion(z=math.sin(k / 2), w=math.cos(k / 2)),
        ),
    )


def main(n: int = 20000) -> None:
    b = BufferCore(cache_time=10.0)
    names = ["f0", "f1", "f2", "f3", "f4", "f5"]
    for i in range(100):  # 10 s of history at 10 Hz per link
        for p, c in itertools.pairwise(names):
            b.set_transform(_tf(p, c, S + i * 100_000_000, 0.01 * i))
    times = [S + 50_000_000 + (i % 90) * 100_000_000 for i in range(n)]
    for label, target, source, use_zero in (
        ("interpolated, 5 links", "f0", "f5", False),
        ("latest common time, 5 links", "f0", "f5", True),
        ("across the tree (f5 -> f2)", "f5", "f2", False),
    ):
        t0 = time.perf_counter()
        for t in times:
            b.lookup_transform(target, source, 0 if use_zero else t)
        us = (time.perf_counter() - t0) / n * 1e6
        print(f"{label:<32} {us:6.1f} us/lookup  (tf2 C++: ~17 us)")


if __name__ == "__main__":
    main()
