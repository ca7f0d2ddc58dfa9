"""Rendering and physics speed of the simulator (printed, never asserted).

    python bench/bench_render.py

Renders the explorer's view at each course target (walls fill much of the view) with each
renderer that loads, at 640x480 and 320x240, and steps both robots' physics.
"""

from __future__ import annotations

import dataclasses
import statistics
import time

from usar_replay.core import msgs
from usar_replay.sim.simulator import Simulator
from usar_replay.world.scenario import course_world


def bench_render(renderer: str, width: int, height: int, frames: int = 20) -> float | None:
    scn = course_world()
    scn = dataclasses.replace(
        scn, camera=dataclasses.replace(scn.camera, width=width, height=height)
    )
    try:
        sim = Simulator(scn, renderer=renderer)
    except RuntimeError:
        return None
    with sim:
        if sim.renderer_name != renderer:
            return None
        times = []
        for i in range(frames):
            tx, ty = scn.targets[i % len(scn.targets)]
            sim.teleport("explorer", tx, ty, i * 0.7)
            t0 = time.perf_counter()
            sim.render_camera()
            times.append(time.perf_counter() - t0)
        return statistics.median(times[2:]) * 1000


def bench_physics(steps: int = 20000) -> float:
    with Simulator(course_world(), renderer="tiny") as sim:
        sim.teleport("explorer", 0.0, -2.5, 0.0)
        for r in ("explorer", "follower"):
            sim.set_cmd_vel(r, msgs.Twist(linear=msgs.Vector3(x=0.1), angular=msgs.Vector3(z=0.5)))
        t0 = time.perf_counter()
        sim.step(steps)
        return steps / (time.perf_counter() - t0)


def main() -> None:
    print("renderer  size      ms/frame (median)")
    for renderer in ("tiny", "egl"):
        for w, h in ((640, 480), (320, 240)):
            ms = bench_render(renderer, w, h)
            shown = "does not load here" if ms is None else f"{ms:8.1f}"
            print(f"{renderer:<8}  {w}x{h:<4}  {shown}")
    sps = bench_physics()
    print(
        f"physics: {sps:,.0f} steps/s (both robots moving, collision checked) = "
        f"{sps / 100:,.0f}x real time at 100 Hz"
    )


if __name__ == "__main__":
    main()
