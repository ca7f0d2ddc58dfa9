"""The world as data: walls, obstacles, markers, lookup targets, robot starts, camera, time limit.

Pure data, no I/O beyond TOML text: the simulator builds from it, the navigator grids it, the
mission reads its parameters, and the log carries it so a recording is self-contained.
The course world of ENPM809Y (``../shared/course-world.md``) is :func:`course_world`.

All poses are in the ``map`` frame (REP-103: x east, y north, z up, yaw counter-clockwise from +x),
metres and radians.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

__all__ = [
    "Box",
    "Cylinder",
    "Sphere",
    "Marker",
    "RobotStart",
    "CameraSettings",
    "Scenario",
    "course_world",
    "WALL_THICKNESS",
    "WALL_HEIGHT",
]

WALL_THICKNESS = 0.15
WALL_HEIGHT = 1.0


@dataclass(frozen=True, slots=True, kw_only=True)
class Box:
    """An upright box (a wall or a box obstacle): centre, full sizes along its own x/y/z, yaw."""

    name: str
    x: float
    y: float
    z: float
    size_x: float
    size_y: float
    size_z: float
    yaw: float = 0.0


@dataclass(frozen=True, slots=True, kw_only=True)
class Cylinder:
    """An upright cylinder standing on the floor: centre (x, y), radius, height."""

    name: str
    x: float
    y: float
    radius: float
    height: float


@dataclass(frozen=True, slots=True, kw_only=True)
class Sphere:
    """A sphere resting on the floor (centre z = radius)."""

    name: str
    x: float
    y: float
    radius: float


@dataclass(frozen=True, slots=True, kw_only=True)
class Marker:
    """A printed ArUco marker: its face points along its own +x axis (yaw in ``map``)."""

    id: int
    x: float
    y: float
    z: float = 0.2
    yaw: float = 0.0
    size: float = 0.15
    dictionary: str = "DICT_4X4_50"


@dataclass(frozen=True, slots=True, kw_only=True)
class RobotStart:
    """A robot's name (its tf prefix is ``<name>_tf/``) and its start pose in ``map``."""

    name: str
    x: float
    y: float
    yaw: float = 0.0


@dataclass(frozen=True, slots=True, kw_only=True)
class CameraSettings:
    """The explorer's RGB camera: image size, rate, horizontal FOV, encoding of recorded frames."""

    width: int = 640
    height: int = 480
    rate_hz: float = 10.0
    hfov: float = 1.3439
    encoding: str = "png"


@dataclass(frozen=True, slots=True, kw_only=True)
class Scenario:
    """A whole world and its mission parameters.

    ``targets`` are ``aruco_lookup_locations/target_1..target_N`` in visiting order.
    """

    name: str
    walls: tuple[Box, ...]
    boxes: tuple[Box, ...] = ()
    cylinders: tuple[Cylinder, ...] = ()
    spheres: tuple[Sphere, ...] = ()
    markers: tuple[Marker, ...] = ()
    targets: tuple[tuple[float, float], ...] = ()
    explorer: RobotStart = field(default_factory=lambda: RobotStart(name="explorer", x=-4.0, y=2.5))
    follower: RobotStart = field(default_factory=lambda: RobotStart(name="follower", x=-4.0, y=3.5))
    camera: CameraSettings = field(default_factory=CameraSettings)
    time_limit_s: float = 600.0
    seed: int | None = None

    def parameters(self) -> dict[str, list[float]]:
        """The ROS parameters the mission reads: ``aruco_lookup_locations/target_k`` -> [x, y]."""
        return {
            f"aruco_lookup_locations/target_{i + 1}": [t[0], t[1]]
            for i, t in enumerate(self.targets)
        }


def _wall(name: str, x: float, y: float, yaw: float, length: float) -> Box:
    return Box(
        name=name,
        x=x,
        y=y,
        z=WALL_HEIGHT / 2,
        size_x=length,
        size_y=WALL_THICKNESS,
        size_z=WALL_HEIGHT,
        yaw=yaw,
    )


def course_world() -> Scenario:
    """The ENPM809Y Fall 2021 "US&R Simplified" world, from ``course-world.md``."""
    pi = math.pi
    walls = (
        _wall("west_outer", -5.033, 0.166, -pi / 2, 8.0),
        _wall("east_outer", 8.567, 0.166, pi / 2, 8.0),
        _wall("south_outer", 1.767, -3.759, 0.0, 13.75),
        _wall("north_outer", 1.767, 4.091, pi, 13.75),
        _wall("divider_west", -2.389, 0.037, -0.000773, 5.32209),
        _wall("divider_east", 5.602, 0.059, 0.0, 6.0),
        _wall("start_strip", -3.095, 1.930, 0.0, 4.0),
        _wall("north_centre", 2.904, 1.462, pi, 4.0),
        _wall("north_east", 4.829, 2.762, -pi / 2, 2.75),
        _wall("diagonal_sw", 0.847, -1.091, -1.04726, 2.75),
        _wall("diagonal_se", 4.675, -2.599, 1.0472, 2.75),
    )
    boxes = (
        Box(name="box_a", x=-3.487, y=-1.494, z=0.5, size_x=1.0, size_y=1.0, size_z=1.0),
        Box(
            name="box_b",
            x=0.099,
            y=2.673,
            z=0.328,
            size_x=1.0,
            size_y=0.437,
            size_z=0.657,
            yaw=2.031,
        ),
    )
    cyl_r, cyl_h = 0.2821, 0.5851
    cylinders = tuple(
        Cylinder(name=f"cylinder_{i}", x=x, y=y, radius=cyl_r, height=cyl_h)
        for i, (x, y) in enumerate(
            [(1.914, 3.688), (-1.490, -1.864), (6.680, -0.986), (6.504, 2.500), (2.978, -1.257)]
        )
    )
    spheres = (
        Sphere(name="sphere_0", x=6.535, y=-2.425, radius=0.2914),
        Sphere(name="sphere_1", x=-4.593, y=1.524, radius=0.2914),
    )
    markers = (
        Marker(id=0, x=-1.80731, y=4.0, yaw=-1.5707),
        Marker(id=1, x=-2.44281, y=1.83165, yaw=-1.5707),
        Marker(id=2, x=8.46068, y=-2.0, yaw=pi),
        Marker(id=3, x=0.618445, y=-0.878635, yaw=-2.56707),
    )
    targets = (
        (-1.752882, 3.246192),
        (-2.510293, 1.125585),
        (-0.289296, -1.282680),
        (7.710214, -1.716889),
    )
    return Scenario(
        name="course",
        walls=walls,
        boxes=boxes,
        cylinders=cylinders,
        spheres=spheres,
        markers=markers,
        targets=targets,
    )
