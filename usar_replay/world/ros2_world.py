"""The ROS 2 final project's world: one room, one marker, four origin frames, seeded variants.

The course's ROS 2 edition (a Turtlebot3 ``robot1`` in Gazebo) gives the mission these
parameters (``final_params.yaml``)::

    aruco_target: {x: 3.6, y: 1.2}            # the first goal; a marker is in view from there
    final_destination:
      frame_id: origin1                       # a static frame of the world
      aruco_0: {x: 1.0, y: 1.0}               # the destination for marker ID 0, in frame_id
      aruco_1: {x: 1.0, y: -1.0}  ...

The world's own data (what the course's launch file and Gazebo world hold) lives in the scenario's
``[task]`` table: the robot's start (``robot1.x/y/yaw``), the origin frames (``originN.x/y/yaw``
in ``map``), ``final_destination.frame_id`` and ``final_destination.aruco_K.x/y``. The scenario's
single lookup target (``aruco_lookup_locations.target_1``) is ``aruco_target``, its single marker
the one the robot must read.

The robot starts at the ``map`` origin facing +x, as it spawns at Gazebo's world origin, so
``map`` and ``robot1/odom`` coincide and ``aruco_target`` means the same in both (the course's
``bot_controller`` took it in odom).

Seeded variants (:func:`make_ros2_variant`) change what the project says may change: the marker's
ID, which origin frame the destinations are in, the destinations and the origin poses. A world is
accepted (:func:`check_ros2`) when the marker is in view from ``aruco_target`` and every
destination is reachable from it.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from usar_replay.core import contract
from usar_replay.core.errors import InvalidScenario
from usar_replay.core.rotations import wrap_angle
from usar_replay.world.nav import Navigator, NavStatus, PlanningGrid
from usar_replay.world.scenario import Box, Marker, Scenario, wall
from usar_replay.world.world_key import WorldKey

__all__ = [
    "ASSIGNMENT",
    "MARKER_IDS",
    "Ros2Task",
    "check_ros2",
    "make_ros2_variant",
    "ros2_final_world",
    "task_of",
]

ASSIGNMENT = "ros2-final"
MARKER_IDS = (0, 1, 2, 3)
"""The project's markers: ``final_destination.aruco_0..3``."""
MAX_RANGE = 1.5
"""m; the marker must be at most this far from ``aruco_target`` (the detector's reliable range)."""
MAX_OBLIQUE = math.radians(35)
MAX_TRIES = 400
COURSE_DESTINATIONS = ((1.0, 1.0), (1.0, -1.0), (-1.0, -1.0), (-1.0, 1.0))
"""``final_destination.aruco_0..3`` as the course's parameter file gave them."""


@dataclasses.dataclass(frozen=True, slots=True)
class Ros2Task:
    """The project's world data, read from a scenario (:func:`task_of`)."""

    start: tuple[float, float, float]
    """robot1's start in ``map`` (x, y, yaw)."""
    aruco_target: tuple[float, float]
    origins: dict[str, tuple[float, float, float]]
    """``originN`` -> its pose in ``map`` (x, y, yaw)."""
    frame_id: str
    """``final_destination.frame_id``: the origin frame the destinations are given in."""
    destinations: dict[int, tuple[float, float]]
    """Marker ID -> ``final_destination.aruco_<ID>`` (x, y) in ``frame_id``."""
    marker_id: int
    """The ID of the world's one marker."""

    def in_map(self, marker_id: int, frame: str | None = None) -> tuple[float, float]:
        """Where ``aruco_<marker_id>`` is in ``map`` when read in ``frame`` (default the
        parameter's ``frame_id``; ``map`` gives the values themselves)."""
        dx, dy = self.destinations[marker_id]
        fx, fy, fyaw = self.origins.get(frame or self.frame_id, (0.0, 0.0, 0.0))
        c, s = math.cos(fyaw), math.sin(fyaw)
        return (fx + c * dx - s * dy, fy + s * dx + c * dy)

    @property
    def destination(self) -> tuple[float, float]:
        """The true final destination in ``map`` (for the world's marker)."""
        return self.in_map(self.marker_id)


def _get(scn: Scenario, values: dict[str, float | str], key: str) -> float:
    if key not in values:
        raise InvalidScenario(f"{scn.name}: task.{key}: missing (the {ASSIGNMENT} world needs it)")
    v = values[key]
    if isinstance(v, str):
        raise InvalidScenario(f"{scn.name}: task.{key}: must be a number, got {v!r}")
    return float(v)


def task_of(scn: Scenario) -> Ros2Task:
    """The project's data of a ``ros2-final`` scenario; :class:`InvalidScenario` names the first
    missing or bad field."""
    values = dict(scn.task)
    if len(scn.markers) != 1:
        raise InvalidScenario(
            f"{scn.name}: markers: the {ASSIGNMENT} world has exactly one marker, "
            f"got {len(scn.markers)}"
        )
    marker = scn.markers[0]
    if marker.id not in MARKER_IDS:
        raise InvalidScenario(f"{scn.name}: markers[0].id: must be 0..3, got {marker.id}")
    if len(scn.targets) != 1:
        raise InvalidScenario(
            f"{scn.name}: aruco_lookup_locations: the {ASSIGNMENT} world has one target "
            "(aruco_target)"
        )
    frame = values.get("final_destination.frame_id")
    if frame not in contract.ORIGIN_FRAMES:
        raise InvalidScenario(
            f"{scn.name}: task.final_destination.frame_id: must be one of "
            f"{', '.join(contract.ORIGIN_FRAMES)}, got {frame!r}"
        )
    origins = {
        o: (_get(scn, values, f"{o}.x"), _get(scn, values, f"{o}.y"), _get(scn, values, f"{o}.yaw"))
        for o in contract.ORIGIN_FRAMES
    }
    destinations = {
        k: (
            _get(scn, values, f"final_destination.aruco_{k}.x"),
            _get(scn, values, f"final_destination.aruco_{k}.y"),
        )
        for k in MARKER_IDS
    }
    start = (
        _get(scn, values, "robot1.x"),
        _get(scn, values, "robot1.y"),
        _get(scn, values, "robot1.yaw"),
    )
    return Ros2Task(
        start=start,
        aruco_target=(float(scn.targets[0][0]), float(scn.targets[0][1])),
        origins=origins,
        frame_id=str(frame),
        destinations=destinations,
        marker_id=marker.id,
    )


def _task_pairs(
    start: tuple[float, float, float],
    origins: dict[str, tuple[float, float, float]],
    frame_id: str,
    destinations: dict[int, tuple[float, float]],
) -> tuple[tuple[str, float | str], ...]:
    pairs: list[tuple[str, float | str]] = [
        ("robot1.x", start[0]),
        ("robot1.y", start[1]),
        ("robot1.yaw", start[2]),
        ("final_destination.frame_id", frame_id),
    ]
    for name, (x, y, yaw) in origins.items():
        pairs += [(f"{name}.x", x), (f"{name}.y", y), (f"{name}.yaw", yaw)]
    for k, (x, y) in destinations.items():
        pairs += [(f"final_destination.aruco_{k}.x", x), (f"final_destination.aruco_{k}.y", y)]
    return tuple(sorted(pairs))


def ros2_final_world() -> Scenario:
    """The built-in world: a 7 m x 6 m room, robot1 at the origin, the marker (ID 1) on a crate
    1.1 m west of ``aruco_target``, destinations in ``origin1`` (the course's values)."""
    pi = math.pi
    walls = (
        wall("west", -1.5, 0.0, pi / 2, 6.0),
        wall("east", 5.5, 0.0, pi / 2, 6.0),
        wall("south", 2.0, -3.0, 0.0, 7.15),
        wall("north", 2.0, 3.0, 0.0, 7.15),
    )
    # the marker is on the crate's east face, behind a robot arriving from the west: it must
    # turn to see it, as the project's robot did
    boxes = (Box(name="crate", x=2.2, y=1.2, z=0.3, size_x=0.6, size_y=0.6, size_z=0.6),)
    marker = Marker(id=1, x=2.2 + 0.3 + 0.005, y=1.2, yaw=0.0)
    origins = {
        "origin1": (1.5, -0.5, 0.0),
        "origin2": (3.5, -1.5, pi / 2),
        "origin3": (0.5, -1.0, pi),
        "origin4": (3.0, 0.5, -pi / 2),
    }
    return Scenario(
        name="ros2_final",
        walls=walls,
        boxes=boxes,
        markers=(marker,),
        targets=((3.6, 1.2),),
        time_limit_s=90.0,
        assignment=ASSIGNMENT,
        task=_task_pairs(
            (0.0, 0.0, 0.0),
            origins,
            "origin1",
            dict(zip(MARKER_IDS, COURSE_DESTINATIONS, strict=True)),
        ),
    )


def _reachable(grid: PlanningGrid, start: tuple[float, float], goal: tuple[float, float]) -> bool:
    if not grid.is_free(*goal):
        return False
    nav = Navigator(grid)
    path = nav.set_goal(
        goal[0],
        goal[1],
        None,
        xy_tolerance=0.05,
        yaw_tolerance=0.17,
        t_ns=1,
        start=(start[0], start[1], 0.0),
    )
    return bool(path) and nav.status is not NavStatus.FAILED


def check_ros2(scn: Scenario, grid: PlanningGrid | None = None) -> str | None:
    """None when the world is playable, else the first problem: the marker must be in view
    from ``aruco_target`` (line of sight, within :data:`MAX_RANGE`, at most
    :data:`MAX_OBLIQUE` off its face), ``aruco_target`` reachable from the start and every
    destination (in ``final_destination.frame_id``) reachable from ``aruco_target``."""
    task = task_of(scn)
    grid = grid or PlanningGrid.from_scenario(scn)
    m = scn.markers[0]
    tx, ty = task.aruco_target
    d = math.dist((tx, ty), (m.x, m.y))
    oblique = abs(wrap_angle(math.atan2(ty - m.y, tx - m.x) - m.yaw))
    if d > MAX_RANGE or oblique > MAX_OBLIQUE:
        return f"the marker is {d:.2f} m and {math.degrees(oblique):.0f} deg off aruco_target"
    if not grid.line_clear((tx, ty), (m.x, m.y), skip_end=0.08):
        return "the marker is not in line of sight from aruco_target"
    if not _reachable(grid, task.start[:2], (tx, ty)):
        return "aruco_target is not reachable from robot1's start"
    for k in MARKER_IDS:
        dest = task.in_map(k)
        if not _reachable(grid, (tx, ty), dest):
            return (
                f"final_destination.aruco_{k} in {task.frame_id} is ({dest[0]:.2f}, "
                f"{dest[1]:.2f}) in map: not reachable"
            )
    return None


def make_ros2_variant(base: Scenario, seed: int, key: WorldKey | None = None) -> Scenario:
    """A seeded variant of ``base`` (same room, marker position and ``aruco_target``): another
    marker ID, another origin frame, other origin poses and destinations. Candidates are drawn
    from ``numpy.random.default_rng(seed)`` until one passes :func:`check_ros2`; with a world
    ``key``, from HMAC-SHA256(key, seed) instead (:mod:`usar_replay.world.world_key`)."""
    task = task_of(base)
    grid = PlanningGrid.from_scenario(base)
    rng = np.random.default_rng(seed if key is None else key.rng_seed(seed))
    walls_x = [w.x for w in base.walls]
    walls_y = [w.y for w in base.walls]
    x0, x1 = min(walls_x) + 1.0, max(walls_x) - 1.0
    y0, y1 = min(walls_y) + 1.0, max(walls_y) - 1.0
    for _ in range(MAX_TRIES):
        marker_id = int(rng.integers(0, len(MARKER_IDS)))
        frame = contract.ORIGIN_FRAMES[int(rng.integers(0, len(contract.ORIGIN_FRAMES)))]
        origins = {
            o: (
                round(float(rng.uniform(x0, x1)), 3),
                round(float(rng.uniform(y0, y1)), 3),
                round(float(rng.choice([0.0, math.pi / 2, math.pi, -math.pi / 2])), 6),
            )
            for o in contract.ORIGIN_FRAMES
        }
        destinations = {
            k: (
                round(sx * float(rng.uniform(0.6, 1.4)), 3),
                round(sy * float(rng.uniform(0.6, 1.4)), 3),
            )
            for k, (sx, sy) in zip(MARKER_IDS, COURSE_DESTINATIONS, strict=True)
        }
        marker = dataclasses.replace(base.markers[0], id=marker_id)
        candidate = dataclasses.replace(
            base,
            markers=(marker,),
            seed=seed,
            world_key="" if key is None else key.digest,
            task=_task_pairs(task.start, origins, frame, destinations),
        )
        if check_ros2(candidate, grid) is None:
            return candidate
    raise InvalidScenario(f"{base.name}: no playable variant for seed {seed}")
