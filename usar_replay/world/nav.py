"""Navigation, move_base-like: a costmap from the scenario, a global planner, a local controller.

Pure numpy/scipy, deterministic, no clock: time comes in as integer nanoseconds with each pose.

* :class:`PlanningGrid` rasterises the scenario's walls and obstacles at 0.05 m (the course
  costmap's resolution; never drawn by hand), computes each cell's distance to the nearest
  obstacle (``scipy.ndimage.distance_transform_edt``) and a move_base-like inflation cost that
  decays as ``exp(-3.0 (d - r))`` within 1.0 m. A cell is *free* when the robot, rotating about
  base_footprint, fits there: its distance is at least :attr:`PlanningGrid.robot_radius`.
* :func:`course_goal` decides a goal as the course's ``global_planner`` would: a goal whose
  costmap cell is lethal or within the footprint's inscribed radius of an obstacle
  (:class:`GoalLimits`, from the package's costmap parameters) has no plan and is refused,
  unless the planner's ``default_tolerance`` reaches a cell that has one.
* :func:`plan` is Dijkstra (scipy's compiled ``csgraph.dijkstra``) on the 8-connected free cells,
  each step weighted by its length times ``1 + cost_weight * cost``, so paths keep off walls;
  the graph is built once per grid.
* :class:`Navigator` follows the plan with pure pursuit (look-ahead 0.35 m; rotate in place when
  the heading error exceeds 0.6 rad), within the waffle's velocity and acceleration limits, stops
  within the goal's xy tolerance, then turns to the goal's yaw if one is given. When the robot
  makes no progress for :attr:`DriveLimits.stuck_time_s` it backs up and replans (up to
  :attr:`DriveLimits.max_recoveries` times), then fails with a reason, as move_base's recovery
  behaviours do.
"""

from __future__ import annotations

import enum
import functools
import itertools
import math
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
from scipy import ndimage
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from usar_replay.core import contract, msgs
from usar_replay.core.rotations import wrap_angle
from usar_replay.world.scenario import Scenario, building_extent

__all__ = [
    "TEMPLATE_GOAL_LIMITS",
    "course_goal",
    "goal_status",
    "grid_from_msg",
    "grid_to_msg",
    "DriveLimits",
    "GoalLimits",
    "NavStatus",
    "Navigator",
    "PlanningGrid",
    "PlanResult",
    "plan",
    "robot_disc",
]

ROBOT_RADIUS = 0.26
"""m; the waffle's footprint rotating about base_footprint reaches 0.257 m."""


BODY_OFFSET = -0.064
"""m; the waffle's body centre is this far along x from base_footprint (behind the axle)."""
BODY_RADIUS = 0.21
"""m; the footprint's circumscribed radius about the body centre."""


def robot_disc(x: float, y: float, yaw: float) -> tuple[float, float, float]:
    """A robot standing at (x, y, yaw) as a round obstacle (x, y, radius) for another's map."""
    return (x + BODY_OFFSET * math.cos(yaw), y + BODY_OFFSET * math.sin(yaw), BODY_RADIUS)


class NavStatus(enum.Enum):
    IDLE = "idle"
    ACTIVE = "active"
    SUCCEEDED = "succeeded"
    FAILED = "failed"


@dataclass(frozen=True, slots=True, kw_only=True)
class DriveLimits:
    """The controller's limits and gains (the waffle's and TurtleBot3's DWA defaults)."""

    max_linear: float = 0.26
    max_angular: float = 1.82
    max_linear_accel: float = 2.5
    max_angular_accel: float = 3.2
    lookahead: float = 0.35
    rotate_in_place_above: float = 0.6
    heading_gain: float = 2.0
    slow_down_within: float = 0.5
    min_linear: float = 0.04
    stuck_time_s: float = 8.0
    progress_m: float = 0.05
    backup_speed: float = 0.1
    backup_time_s: float = 1.5
    max_recoveries: int = 2


@dataclass(frozen=True, slots=True, kw_only=True)
class GoalLimits:
    """What decides whether the course's global planner has a plan to a goal: the costmap's
    inscribed radius (the footprint's, padded), its inflation radius (no inscribed cost is
    painted beyond it) and the planner's ``default_tolerance``; ``source`` says where they
    were read (a package's launch and YAML files, or the course template's defaults)."""

    inscribed_m: float = 0.087
    """The course template's footprint [[-0.205, -0.155], [-0.205, 0.155], [0.077, 0.155],
    [0.077, -0.155]] padded by costmap_2d's default ``footprint_padding`` 0.01 m."""
    inflation_m: float = 1.0
    """The template's ``inflation_radius``."""
    default_tolerance_m: float = 0.0
    """The template's global planner's ``default_tolerance``."""
    source: str = "the course template's costmap and planner defaults"

    @property
    def blocked_m(self) -> float:
        """A cell this near an obstacle (cell centre to cell centre, as costmap_2d measures)
        costs ``INSCRIBED_INFLATED_OBSTACLE`` or more: no plan ends there."""
        return min(self.inscribed_m, self.inflation_m)


TEMPLATE_GOAL_LIMITS = GoalLimits()


@dataclass(frozen=True, slots=True)
class PlanResult:
    ok: bool
    path: tuple[tuple[float, float], ...]
    reason: str = ""
    length_m: float = 0.0


class PlanningGrid:
    """The costmap: occupancy, distance to obstacles and inflation cost, rows = y, cols = x."""

    def __init__(
        self,
        occupied: np.ndarray,
        origin: tuple[float, float],
        resolution: float,
        *,
        robot_radius: float = ROBOT_RADIUS,
        inflation_radius: float = 1.0,
        cost_scaling: float = 3.0,
    ) -> None:
        self.occupied = occupied
        self.origin = origin
        self.resolution = resolution
        self.height: int = int(occupied.shape[0])
        self.width: int = int(occupied.shape[1])
        self.robot_radius = robot_radius
        self.inflation_radius = inflation_radius
        self.cost_scaling = cost_scaling
        self.distance = ndimage.distance_transform_edt(~occupied) * resolution
        over = np.maximum(self.distance - robot_radius, 0.0)
        cost = np.exp(-cost_scaling * over)
        cost[self.distance >= inflation_radius] = 0.0
        cost[self.distance < robot_radius] = 1.0
        self.cost = cost
        self.free = self.distance >= robot_radius

    @classmethod
    def from_scenario(
        cls,
        scn: Scenario,
        resolution: float = 0.05,
        *,
        robot_radius: float = ROBOT_RADIUS,
        margin: float = 0.5,
    ) -> PlanningGrid:
        """Rasterise every wall, box, cylinder and sphere footprint (a cell is occupied when its
        centre is within half a cell of a shape, so thin walls never fall between centres)."""
        x0, y0, x1, y1 = building_extent(scn)
        ox, oy = x0 - margin, y0 - margin
        w = math.ceil((x1 - x0 + 2 * margin) / resolution)
        h = math.ceil((y1 - y0 + 2 * margin) / resolution)
        gx, gy = _cell_centres((ox, oy), resolution, h, w)
        occ = np.zeros((h, w), dtype=bool)
        pad = resolution / 2
        for b in (*scn.walls, *scn.boxes):
            c, s = math.cos(b.yaw), math.sin(b.yaw)
            lx = (gx - b.x) * c + (gy - b.y) * s
            ly = -(gx - b.x) * s + (gy - b.y) * c
            occ |= (np.abs(lx) <= b.size_x / 2 + pad) & (np.abs(ly) <= b.size_y / 2 + pad)
        discs = [(c.x, c.y, c.radius) for c in scn.cylinders]
        discs += [(s.x, s.y, s.radius) for s in scn.spheres]
        _add_discs(occ, gx, gy, discs, pad)
        return cls(occ, (ox, oy), resolution, robot_radius=robot_radius)

    def with_discs(self, discs: Iterable[tuple[float, float, float]]) -> PlanningGrid:
        """This grid plus round obstacles ``(x, y, radius)``: what a robot's sensors would add
        to its costmap, e.g. another robot parked in the way."""
        gx, gy = _cell_centres(self.origin, self.resolution, self.height, self.width)
        occ = self.occupied.copy()
        _add_discs(occ, gx, gy, discs, self.resolution / 2)
        return PlanningGrid(
            occ,
            self.origin,
            self.resolution,
            robot_radius=self.robot_radius,
            inflation_radius=self.inflation_radius,
            cost_scaling=self.cost_scaling,
        )

    # -- coordinates -------------------------------------------------------------------------

    def world_to_cell(self, x: float, y: float) -> tuple[int, int]:
        """(row, col) of the cell holding (x, y); may be outside the grid."""
        return (
            math.floor((y - self.origin[1]) / self.resolution),
            math.floor((x - self.origin[0]) / self.resolution),
        )

    def cell_to_world(self, row: int, col: int) -> tuple[float, float]:
        return (
            self.origin[0] + (col + 0.5) * self.resolution,
            self.origin[1] + (row + 0.5) * self.resolution,
        )

    def inside(self, row: int, col: int) -> bool:
        return 0 <= row < self.height and 0 <= col < self.width

    def distance_to_obstacle(self, x: float, y: float) -> float:
        """Metres from (x, y)'s cell to the nearest occupied cell (0 inside one or outside)."""
        r, c = self.world_to_cell(x, y)
        return float(self.distance[r, c]) if self.inside(r, c) else 0.0

    def is_free(self, x: float, y: float) -> bool:
        """Whether the robot, centred at (x, y), can stand and rotate there."""
        r, c = self.world_to_cell(x, y)
        return self.inside(r, c) and bool(self.free[r, c])

    def line_clear(
        self, a: tuple[float, float], b: tuple[float, float], skip_end: float = 0.0
    ) -> bool:
        """No occupied cell on the segment a -> b, ignoring its last ``skip_end`` metres (the
        wall a marker hangs on), sampled every half cell: a line of sight on this map."""
        length = math.dist(a, b)
        n = max(int(length / (self.resolution / 2)), 1)
        for i in range(n + 1):
            f = i / n
            if f * length > length - skip_end:
                break
            x, y = a[0] + (b[0] - a[0]) * f, a[1] + (b[1] - a[1]) * f
            if self.distance_to_obstacle(x, y) <= 0.0:
                return False
        return True

    def nearest_free(self, x: float, y: float, max_dist: float = 0.5) -> tuple[float, float] | None:
        """The centre of the free cell nearest to (x, y), within ``max_dist``; None if none."""
        r0, c0 = self.world_to_cell(x, y)
        n = math.ceil(max_dist / self.resolution)
        best: tuple[float, int, int] | None = None
        for r in range(max(r0 - n, 0), min(r0 + n + 1, self.height)):
            for c in range(max(c0 - n, 0), min(c0 + n + 1, self.width)):
                if self.free[r, c]:
                    cx, cy = self.cell_to_world(r, c)
                    d = math.hypot(cx - x, cy - y)
                    if d <= max_dist and (best is None or (d, r, c) < best):
                        best = (d, r, c)
        return None if best is None else self.cell_to_world(best[1], best[2])

    @functools.cached_property
    def _graph(self) -> csr_matrix:
        """The 8-connected graph of free cells, weighted by length x (1 + 4 cost)."""
        h, w = self.height, self.width
        idx = np.arange(h * w).reshape(h, w)
        rows: list[np.ndarray] = []
        cols: list[np.ndarray] = []
        vals: list[np.ndarray] = []
        for dr, dc in ((0, 1), (1, 0), (1, 1), (1, -1), (0, -1), (-1, 0), (-1, -1), (-1, 1)):
            r0, r1 = max(0, -dr), min(h, h - dr)
            c0, c1 = max(0, -dc), min(w, w - dc)
            src = idx[r0:r1, c0:c1]
            dst = idx[r0 + dr : r1 + dr, c0 + dc : c1 + dc]
            ok = self.free[r0:r1, c0:c1] & self.free[r0 + dr : r1 + dr, c0 + dc : c1 + dc]
            step = math.hypot(dr, dc) * self.resolution
            weight = step * (1.0 + 4.0 * self.cost[r0 + dr : r1 + dr, c0 + dc : c1 + dc])
            rows.append(src[ok])
            cols.append(dst[ok])
            vals.append(weight[ok])
        return csr_matrix(
            (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
            shape=(h * w, h * w),
        )


def course_goal(
    grid: PlanningGrid, x: float, y: float, limits: GoalLimits = TEMPLATE_GOAL_LIMITS
) -> tuple[tuple[float, float] | None, str]:
    """The goal as the course's global planner takes it: ``((x, y), "")`` where its costmap
    cell is plannable (neither lethal nor within the inscribed radius of an obstacle); the
    nearest plannable cell within ``default_tolerance`` where one is; else ``(None, why)``
    (move_base aborts it: issue 51, a follower goal 0.11 m from a cylinder's surface had no
    plan on the course). A plannable goal inside usar's own clearance (the circumscribed
    radius its controller keeps free) is the caller's to move."""
    r0, c0 = grid.world_to_cell(x, y)
    blocked = limits.blocked_m + 1e-9

    def plannable(r: int, c: int) -> bool:
        return grid.inside(r, c) and float(grid.distance[r, c]) > blocked

    if plannable(r0, c0):
        return (x, y), ""
    n = math.ceil(limits.default_tolerance_m / grid.resolution)
    best: tuple[float, int, int] | None = None
    for r in range(r0 - n, r0 + n + 1):
        for c in range(c0 - n, c0 + n + 1):
            if plannable(r, c):
                cx, cy = grid.cell_to_world(r, c)
                d = math.hypot(cx - x, cy - y)
                if d <= limits.default_tolerance_m and (best is None or (d, r, c) < best):
                    best = (d, r, c)
    if best is not None:
        return grid.cell_to_world(best[1], best[2]), ""
    where = "in an obstacle" if grid.distance_to_obstacle(x, y) <= 0.0 else (
        f"within the footprint's inscribed radius ({limits.inscribed_m:.3f} m) of an obstacle"
    )
    return None, (
        f"goal ({x:.3f}, {y:.3f}) is {where}: the global planner has no plan to it "
        f"(default_tolerance {limits.default_tolerance_m:g} m; {limits.source})"
    )


def _cell_centres(
    origin: tuple[float, float], resolution: float, height: int, width: int
) -> tuple[np.ndarray, np.ndarray]:
    """World x and y of every cell centre, as two (height, width) arrays."""
    xs = origin[0] + (np.arange(width) + 0.5) * resolution
    ys = origin[1] + (np.arange(height) + 0.5) * resolution
    gx, gy = np.meshgrid(xs, ys)
    return gx, gy


def _add_discs(
    occ: np.ndarray,
    gx: np.ndarray,
    gy: np.ndarray,
    discs: Iterable[tuple[float, float, float]],
    pad: float,
) -> None:
    """Mark the cells whose centre is within ``radius + pad`` of each disc (x, y, radius)."""
    for x, y, r in discs:
        occ |= np.hypot(gx - x, gy - y) <= r + pad


def plan(grid: PlanningGrid, start: tuple[float, float], goal: tuple[float, float]) -> PlanResult:
    """The cheapest path of free cells from ``start`` to ``goal``, as world points."""
    gx, gy = goal
    if not grid.is_free(gx, gy):
        return PlanResult(False, (), f"goal ({gx:.3f}, {gy:.3f}) is in collision")
    sx, sy = start
    if not grid.is_free(sx, sy):
        near = grid.nearest_free(sx, sy, 0.5)
        if near is None:
            return PlanResult(False, (), f"start ({sx:.3f}, {sy:.3f}) is in collision")
        sx, sy = near
    sr, sc = grid.world_to_cell(sx, sy)
    gr, gc = grid.world_to_cell(gx, gy)
    s_i, g_i = sr * grid.width + sc, gr * grid.width + gc
    # one source given as a one-element array (scipy-stubs type ``indices`` as an array): row 0
    dists, preds = dijkstra(
        grid._graph, directed=True, indices=np.array([s_i]), return_predecessors=True
    )
    dist, pred = dists[0], preds[0]
    if not np.isfinite(dist[g_i]):
        return PlanResult(
            False, (), f"no path from ({start[0]:.3f}, {start[1]:.3f}) to ({gx:.3f}, {gy:.3f})"
        )
    cells = [g_i]
    while cells[-1] != s_i:
        cells.append(int(pred[cells[-1]]))
    cells.reverse()
    pts = [grid.cell_to_world(i // grid.width, i % grid.width) for i in cells]
    pts[0] = (start[0], start[1]) if (sx, sy) == start else pts[0]
    pts[-1] = (gx, gy)
    length = sum(math.dist(a, b) for a, b in itertools.pairwise(pts))
    return PlanResult(True, tuple(pts), "", length)


class _Mode(enum.Enum):
    DRIVE = "drive"
    TURN = "turn"
    BACKUP = "backup"


class Navigator:
    """One robot's move_base: ``set_goal`` then ``update`` with each new pose."""

    def __init__(self, grid: PlanningGrid, limits: DriveLimits | None = None) -> None:
        self.grid = grid
        self.limits = limits or DriveLimits()
        self.status = NavStatus.IDLE
        self.reason = ""
        self.path: tuple[tuple[float, float], ...] = ()
        self._remaining: tuple[float, ...] = ()
        self._goal: tuple[float, float] = (0.0, 0.0)
        self._yaw: float | None = None
        self._xy_tol = 0.05
        self._yaw_tol = 0.17
        self._mode = _Mode.DRIVE
        self._index = 0
        self._last_t: int | None = None
        self._v = 0.0
        self._w = 0.0
        self._best = math.inf
        self._progress_t = 0
        self._recoveries = 0
        self._backup_until = 0

    def set_goal(
        self,
        x: float,
        y: float,
        yaw: float | None,
        *,
        xy_tolerance: float,
        yaw_tolerance: float,
        t_ns: int,
        start: tuple[float, float, float] | None = None,
    ) -> list[tuple[float, float]]:
        """Plan to (x, y); the planned path (empty, with ``status`` FAILED, when impossible)."""
        self._goal, self._yaw = (x, y), yaw
        self._xy_tol, self._yaw_tol = xy_tolerance, yaw_tolerance
        self._mode = _Mode.DRIVE
        self._recoveries = 0
        self._best = math.inf
        self._progress_t = t_ns
        self.status, self.reason = NavStatus.ACTIVE, ""
        self.path = ()
        if start is None:
            return []
        return self._plan(start[0], start[1])

    def _plan(self, x: float, y: float) -> list[tuple[float, float]]:
        result = plan(self.grid, (x, y), self._goal)
        if not result.ok:
            self.status, self.reason = NavStatus.FAILED, result.reason
            self.path = ()
            return []
        self.path = result.path
        # path length left from each point to the goal: progress is measured along the path
        left = [0.0] * len(result.path)
        for i in range(len(result.path) - 2, -1, -1):
            left[i] = left[i + 1] + math.dist(result.path[i], result.path[i + 1])
        self._remaining = tuple(left)
        self._best = math.inf
        self._index = 0
        return list(result.path)

    def cancel(self) -> None:
        self.status, self.reason = NavStatus.IDLE, "cancelled"

    def _limit(self, v: float, w: float, t_ns: int) -> msgs.Twist:
        lim = self.limits
        dt = 0.05 if self._last_t is None else max(min((t_ns - self._last_t) / 1e9, 0.2), 0.0)
        self._last_t = t_ns
        v = max(-lim.max_linear, min(lim.max_linear, v))
        w = max(-lim.max_angular, min(lim.max_angular, w))
        dv, dw = lim.max_linear_accel * dt, lim.max_angular_accel * dt
        v = max(self._v - dv, min(self._v + dv, v))
        w = max(self._w - dw, min(self._w + dw, w))
        self._v, self._w = v, w
        return msgs.Twist(linear=msgs.Vector3(x=v), angular=msgs.Vector3(z=w))

    def _stop(self, t_ns: int) -> msgs.Twist:
        self._last_t = t_ns
        self._v = self._w = 0.0
        return msgs.Twist()

    def update(self, t_ns: int, x: float, y: float, yaw: float) -> msgs.Twist:
        """The cmd_vel for the robot at (x, y, yaw) at sim time ``t_ns``."""
        if self.status is not NavStatus.ACTIVE:
            return self._stop(t_ns)
        lim = self.limits
        if not self.path and not self._plan(x, y):
            return self._stop(t_ns)
        dist = math.hypot(self._goal[0] - x, self._goal[1] - y)
        if self._mode is _Mode.BACKUP:
            if t_ns < self._backup_until:
                return self._limit(-lim.backup_speed, 0.0, t_ns)
            self._mode = _Mode.DRIVE
            self._best, self._progress_t = math.inf, t_ns
            if not self._plan(x, y):
                return self._stop(t_ns)
        if self._mode is _Mode.DRIVE and dist <= self._xy_tol:
            self._mode = _Mode.TURN  # xy reached: latched, as move_base does
        if self._mode is _Mode.TURN:
            err = 0.0 if self._yaw is None else wrap_angle(self._yaw - yaw)
            if abs(err) <= self._yaw_tol:
                self.status = NavStatus.SUCCEEDED
                return self._stop(t_ns)
            w = math.copysign(max(min(abs(lim.heading_gain * err), lim.max_angular), 0.2), err)
            return self._limit(0.0, w, t_ns)
        # stuck detection: progress is the path length still to drive, not the straight-line
        # distance to the goal (a path around a wall leads away from the goal for a while)
        tx, ty = self._lookahead(x, y)
        px, py = self.path[self._index]
        togo = self._remaining[self._index] + math.hypot(px - x, py - y)
        if togo < self._best - lim.progress_m:
            self._best, self._progress_t = togo, t_ns
        elif t_ns - self._progress_t > lim.stuck_time_s * 1e9:
            if self._recoveries >= lim.max_recoveries:
                self.status = NavStatus.FAILED
                self.reason = f"stuck at ({x:.3f}, {y:.3f}) after {self._recoveries} recoveries"
                return self._stop(t_ns)
            self._recoveries += 1
            self._mode = _Mode.BACKUP
            self._backup_until = t_ns + int(lim.backup_time_s * 1e9)
            return self._limit(-lim.backup_speed, 0.0, t_ns)
        err = wrap_angle(math.atan2(ty - y, tx - x) - yaw)
        if abs(err) > lim.rotate_in_place_above:
            return self._limit(0.0, lim.heading_gain * err, t_ns)
        v = lim.max_linear
        if dist < lim.slow_down_within:
            v = max(lim.max_linear * dist / lim.slow_down_within, lim.min_linear)
        look = max(math.hypot(tx - x, ty - y), 1e-6)
        w = 2.0 * v * math.sin(err) / look
        if abs(w) > lim.max_angular:
            v *= lim.max_angular / abs(w)
            w = math.copysign(lim.max_angular, w)
        return self._limit(v, w, t_ns)

    def _lookahead(self, x: float, y: float) -> tuple[float, float]:
        path = self.path
        # advance the progress index to the closest point within a short window ahead
        best_i, best_d = self._index, math.inf
        for i in range(self._index, min(self._index + 40, len(path))):
            d = math.hypot(path[i][0] - x, path[i][1] - y)
            if d < best_d:
                best_i, best_d = i, d
        self._index = best_i
        for i in range(best_i, len(path)):
            if math.hypot(path[i][0] - x, path[i][1] - y) >= self.limits.lookahead:
                return path[i]
        return path[-1]


# --- the grid as nav_msgs/OccupancyGrid (what /map carries) ---------------------------------


def grid_to_msg(grid: PlanningGrid, stamp: msgs.Time) -> msgs.OccupancyGrid:
    """The costmap's occupancy as ``nav_msgs/OccupancyGrid`` (0 free, 100 occupied)."""
    data = np.where(grid.occupied, 100, 0).astype(np.uint8).tobytes()
    return msgs.OccupancyGrid(
        header=msgs.Header(stamp=stamp, frame_id=contract.MAP),
        info=msgs.MapMetaData(
            map_load_time=stamp,
            resolution=grid.resolution,
            width=grid.width,
            height=grid.height,
            origin=msgs.Pose(position=msgs.Point(x=grid.origin[0], y=grid.origin[1])),
        ),
        data=data,
    )


def grid_from_msg(
    msg: msgs.OccupancyGrid, robot_radius: float = contract.WAFFLE.radius
) -> PlanningGrid:
    """A costmap from ``/map``: occupied and unknown cells are obstacles, inflated by the robot.

    The resolution travels as float32; it is read back as the nearest short decimal (0.05, not
    0.0500000007) so grids built from the map and from the scenario agree cell for cell.
    """
    info = msg.info
    cells = np.frombuffer(msg.data, dtype=np.int8).reshape(info.height, info.width)
    occupied = (cells >= 50) | (cells < 0)
    resolution = float(f"{info.resolution:.7g}")
    origin = (info.origin.position.x, info.origin.position.y)
    return PlanningGrid(occupied, origin, resolution, robot_radius=robot_radius)


# --- a goal's outcome as diagnostic_msgs/DiagnosticStatus (what /<robot>/goal_status carries) ---


def goal_status(
    robot: str,
    name: str,
    seq: int,
    ok: bool,
    reason: str,
    pose: tuple[float, float, float] | None,
    started_ns: int,
    ended_ns: int,
) -> msgs.DiagnosticStatus:
    """How a goal ended, as every navigator reports it (the node API's and the ROS 1 bridge's
    move_base): one shape in the log, whoever drove. ``pose`` is the robot's (x, y, yaw) in
    ``map`` at the end (NaN when unknown)."""
    x, y, yaw = pose or (math.nan, math.nan, math.nan)
    return msgs.DiagnosticStatus(
        level=msgs.DiagnosticStatus.OK if ok else msgs.DiagnosticStatus.ERROR,
        name=name,
        message="succeeded" if ok else f"failed: {reason}",
        hardware_id=robot,
        values=(
            msgs.KeyValue(key="goal", value=name),
            msgs.KeyValue(key="seq", value=str(seq)),
            msgs.KeyValue(key="x", value=repr(x)),
            msgs.KeyValue(key="y", value=repr(y)),
            msgs.KeyValue(key="yaw", value=repr(yaw)),
            msgs.KeyValue(key="started_ns", value=str(started_ns)),
            msgs.KeyValue(key="ended_ns", value=str(ended_ns)),
        ),
    )
