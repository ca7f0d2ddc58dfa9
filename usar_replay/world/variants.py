"""Seeded variants of a scenario: "a different environment", as the instructor sets up per demo.

``make_variant(base, seed)`` keeps the building (walls, obstacles, robot starts) and moves every
marker to another wall or obstacle face, then computes a lookup target in front of each. The
random generator is ``numpy.random.default_rng(seed)``: the same seed gives the same world, on
every machine.

A candidate world is accepted only if, for every target:

* the robot fits there (the navigation grid's free space) and the planner reaches it from the
  explorer's start;
* the follower can reach a point in front of its marker with the explorer parked at home;
* its marker is in line of sight, within :data:`MAX_RANGE` and seen at most :data:`MAX_OBLIQUE`
  off the marker's normal (so the detector reads it);
* no other marker in line of sight is closer than its own (the course world has the wrong-marker
  trap, which the mission must handle; generated worlds must not make it worse);
* the whole mission fits the time limit with room to spare: the planned routes (explorer:
  start, targets in order, home; follower: start, markers in ID order, home) driven at full
  speed take at most :data:`MAX_DRIVE_FRACTION` of the limit, leaving the rest for the spins at
  0.1 rad/s (up to 63 s a target) and turns. The course world needs 58% (actual run: 477 s).

Candidates are drawn until one passes (at most :data:`MAX_TRIES`), which keeps the search
deterministic for a given seed.
"""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np

from usar_replay.core.errors import InvalidScenario
from usar_replay.core.rotations import wrap_angle
from usar_replay.world.nav import DriveLimits, Navigator, NavStatus, PlanningGrid, plan, robot_disc
from usar_replay.world.scenario import Box, Marker, Scenario
from usar_replay.world.world_key import WorldKey

__all__ = [
    "MAX_DRIVE_FRACTION",
    "MAX_OBLIQUE",
    "MAX_RANGE",
    "Face",
    "check_variant",
    "drive_time_s",
    "faces",
    "make_variant",
]

MAX_RANGE = 1.5
"""m; a target sees its marker from at most this far (the course's are 0.71-0.99 m)."""
MIN_RANGE = 0.6
MAX_OBLIQUE = math.radians(35)
MAX_TRIES = 400
MAX_DRIVE_FRACTION = 0.7
"""Planned driving time at full speed, as a fraction of the scenario's time limit."""
MARKER_SPACING = 1.5
"""m; markers are at least this far apart, so one view rarely holds two."""


@dataclasses.dataclass(frozen=True, slots=True)
class Face:
    """A flat or round surface a marker can hang on: a centre point, outward normal, width."""

    name: str
    x: float
    y: float
    yaw: float
    width: float
    round_radius: float = 0.0


def _box_faces(b: Box, interior_only: bool) -> list[Face]:
    out = []
    c, s = math.cos(b.yaw), math.sin(b.yaw)
    for sign in (1.0, -1.0):
        # the two long faces (local +-y) and the two ends (local +-x)
        nx, ny = -s * sign, c * sign
        out.append(
            Face(
                f"{b.name}:{'+' if sign > 0 else '-'}y",
                b.x + nx * b.size_y / 2,
                b.y + ny * b.size_y / 2,
                math.atan2(ny, nx),
                b.size_x,
            )
        )
        if not interior_only:
            ex, ey = c * sign, s * sign
            out.append(
                Face(
                    f"{b.name}:{'+' if sign > 0 else '-'}x",
                    b.x + ex * b.size_x / 2,
                    b.y + ey * b.size_x / 2,
                    math.atan2(ey, ex),
                    b.size_y,
                )
            )
    return out


def faces(scn: Scenario) -> list[Face]:
    """Every face of every wall (both sides) and obstacle where a marker could hang."""
    out: list[Face] = []
    for w in scn.walls:
        out += _box_faces(w, interior_only=True)
    for b in scn.boxes:
        out += _box_faces(b, interior_only=False)
    for cyl in scn.cylinders:
        out.append(Face(cyl.name, cyl.x, cyl.y, 0.0, 0.0, round_radius=cyl.radius))
    return out


def _place(face: Face, rng: np.random.Generator) -> tuple[float, float, float]:
    """A marker pose (x, y, yaw) on ``face``, 1 cm proud of the surface."""
    if face.round_radius > 0:
        a = float(rng.uniform(-math.pi, math.pi))
        r = face.round_radius + 0.01
        return (face.x + r * math.cos(a), face.y + r * math.sin(a), a)
    margin = 0.4
    if face.width < 2 * margin + 0.2:
        off = 0.0
    else:
        off = float(rng.uniform(-face.width / 2 + margin, face.width / 2 - margin))
    tx, ty = -math.sin(face.yaw), math.cos(face.yaw)
    nx, ny = math.cos(face.yaw), math.sin(face.yaw)
    return (face.x + tx * off + nx * 0.01, face.y + ty * off + ny * 0.01, face.yaw)


def _sees(grid: PlanningGrid, target: tuple[float, float], m: Marker) -> tuple[bool, float]:
    d = math.dist(target, (m.x, m.y))
    to_target = math.atan2(target[1] - m.y, target[0] - m.x)
    oblique = abs(wrap_angle(to_target - m.yaw))
    visible = oblique < math.pi / 2 and grid.line_clear(target, (m.x, m.y), skip_end=0.08)
    return visible, d


def _reachable(
    grid: PlanningGrid, start: tuple[float, float, float], goal: tuple[float, float]
) -> bool:
    nav = Navigator(grid)
    path = nav.set_goal(
        goal[0], goal[1], None, xy_tolerance=0.05, yaw_tolerance=0.17, t_ns=1, start=start
    )
    return bool(path) and nav.status is not NavStatus.FAILED


def check_variant(scn: Scenario, grid: PlanningGrid | None = None) -> str | None:
    """None when ``scn`` passes every rule of the module docstring, else the first failure.

    A target's own marker is the nearest marker to it; every marker must be some target's own.
    """
    grid = grid or PlanningGrid.from_scenario(scn)
    ex = (scn.explorer.x, scn.explorer.y, scn.explorer.yaw)
    fo = (scn.follower.x, scn.follower.y, scn.follower.yaw)
    # the follower drives while the explorer is parked at home
    fgrid = grid.with_discs([robot_disc(*ex)])
    owners: dict[int, int] = {}
    for k, target in enumerate(scn.targets):
        if not scn.markers:
            return "no markers"
        by_dist = sorted(scn.markers, key=lambda m: (math.dist(target, (m.x, m.y)), m.id))
        m = by_dist[0]
        if m.id in owners:
            return f"target_{k + 1} and target_{owners[m.id] + 1} share marker {m.id}"
        owners[m.id] = k
        if not grid.is_free(*target):
            return f"target_{k + 1} is not free space"
        visible, d = _sees(grid, target, m)
        if not visible or not (MIN_RANGE <= d <= MAX_RANGE):
            return f"target_{k + 1} does not see marker {m.id} within {MAX_RANGE} m"
        for other in by_dist[1:]:
            v2, d2 = _sees(grid, target, other)
            if v2 and d2 <= d + 0.5:
                return f"from target_{k + 1} marker {other.id} is nearly as close as marker {m.id}"
        if not _reachable(grid, ex, target):
            return f"target_{k + 1} is not reachable from the explorer's start"
        approach = _approach(m)
        if not fgrid.is_free(*approach) or not _reachable(fgrid, fo, approach):
            return f"the follower cannot reach marker {m.id}"
    if len(owners) != len(scn.markers):
        return "some marker is no target's marker"
    budget = MAX_DRIVE_FRACTION * scn.time_limit_s
    need = drive_time_s(scn, grid)
    if need > budget:
        return f"the routes take {need:.0f} s of driving, more than {budget:.0f} s"
    return None


def _approach(m: Marker) -> tuple[float, float]:
    return (m.x + math.cos(m.yaw) * 0.35, m.y + math.sin(m.yaw) * 0.35)


def drive_time_s(scn: Scenario, grid: PlanningGrid | None = None) -> float:
    """Seconds of driving at full speed along the planned routes of both robots."""
    grid = grid or PlanningGrid.from_scenario(scn)
    ex = (scn.explorer.x, scn.explorer.y)
    fo = (scn.follower.x, scn.follower.y)
    by_id = sorted(scn.markers, key=lambda m: m.id)
    length = 0.0
    for route in ([ex, *scn.targets, ex], [fo, *(_approach(m) for m in by_id), fo]):
        for a, b in itertools.pairwise(route):
            result = plan(grid, a, b)
            length += result.length_m if result.ok else math.inf
    return length / DriveLimits().max_linear


def make_variant(base: Scenario, seed: int, key: WorldKey | None = None) -> Scenario:
    """The world of ``base`` with its markers moved and targets recomputed, from ``seed``.

    With a world ``key`` (:mod:`usar_replay.world.world_key`) the random stream is seeded by
    HMAC-SHA256(key, seed): the world cannot be derived from the seed without the key, and it
    records the key's digest (``world_key``)."""
    if seed < 0:
        raise InvalidScenario(f"--seed {seed}: must be >= 0")
    rng = np.random.default_rng(seed if key is None else key.rng_seed(seed))
    grid = PlanningGrid.from_scenario(base)
    candidates = faces(base)
    ids = sorted(m.id for m in base.markers)
    template = {m.id: m for m in base.markers}
    for _ in range(MAX_TRIES):
        chosen = rng.choice(len(candidates), size=len(ids), replace=False)
        markers: list[Marker] = []
        targets: list[tuple[float, float]] = []
        ok = True
        for mid, fi in zip(ids, chosen, strict=True):
            x, y, yaw = _place(candidates[int(fi)], rng)
            if any(math.dist((x, y), (o.x, o.y)) < MARKER_SPACING for o in markers):
                ok = False
                break
            front = (x + math.cos(yaw) * 0.05, y + math.sin(yaw) * 0.05)
            if grid.distance_to_obstacle(*front) <= 0.0:
                ok = False  # the face is against another wall or obstacle
                break
            d = float(rng.uniform(0.7, 1.0))
            lateral = float(rng.uniform(-0.15, 0.15))
            tx = x + math.cos(yaw) * d - math.sin(yaw) * lateral
            ty = y + math.sin(yaw) * d + math.cos(yaw) * lateral
            markers.append(dataclasses.replace(template[mid], x=x, y=y, yaw=yaw))
            targets.append((round(tx, 6), round(ty, 6)))
        if not ok:
            continue
        # IDs in a shuffled order, so the follower's ID order differs from the visiting order
        perm = rng.permutation(len(ids))
        markers = [dataclasses.replace(m, id=ids[int(perm[j])]) for j, m in enumerate(markers)]
        variant = dataclasses.replace(
            base,
            name=f"{base.name}-variant",
            markers=tuple(sorted(markers, key=lambda m: m.id)),
            targets=tuple(targets),
            seed=seed,
            world_key="" if key is None else key.digest,
        )
        if check_variant(variant, grid) is None:
            return variant
    raise InvalidScenario(f"--seed {seed}: no valid variant found in {MAX_TRIES} tries")
