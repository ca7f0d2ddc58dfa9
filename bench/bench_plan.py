"""Costmap build, planning and control speed on the course map (printed, not asserted).

python bench/bench_plan.py
"""

from __future__ import annotations

import itertools
import time

from usar_replay.world.nav import Navigator, PlanningGrid, plan
from usar_replay.world.scenario import course_world


def main() -> None:
    scn = course_world()
    t0 = time.perf_counter()
    grid = PlanningGrid.from_scenario(scn)
    build = time.perf_counter() - t0
    t0 = time.perf_counter()
    _ = grid._graph
    graph = time.perf_counter() - t0
    print(
        f"grid {grid.width}x{grid.height} cells: build {build * 1000:.1f} ms, "
        f"planning graph {graph * 1000:.1f} ms (once per grid)"
    )
    route = [(-4.0, 2.5), *scn.targets, (-4.0, 2.5)]
    for i, (a, b) in enumerate(itertools.pairwise(route)):
        t0 = time.perf_counter()
        for _ in range(5):
            result = plan(grid, a, b)
        ms = (time.perf_counter() - t0) / 5 * 1000
        print(f"leg {i + 1}: {result.length_m:6.2f} m planned in {ms:6.1f} ms")
    nav = Navigator(grid)
    nav.set_goal(
        *scn.targets[3], None, xy_tolerance=0.05, yaw_tolerance=0.17, t_ns=0, start=(-4.0, 2.5, 0.0)
    )
    n = 20000
    t0 = time.perf_counter()
    for k in range(n):
        nav.update(k * 50_000_000, -4.0, 2.5, 0.0)
    print(f"controller: {n / (time.perf_counter() - t0):,.0f} updates/s (incl. a replan per 100)")


if __name__ == "__main__":
    main()
