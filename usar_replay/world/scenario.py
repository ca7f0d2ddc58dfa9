"""The world as data: walls, obstacles, markers, lookup targets, robot starts, camera, time limit.

Pure data, no I/O: the simulator builds from it, the navigator grids it, the mission reads its
parameters, and the log carries it so a recording is self-contained. The course world of
ENPM809Y (``../shared/course-world.md``) is :func:`course_world`. What a world may hold (ranges,
counts, names: :func:`validate`) is checked here, for constructed worlds and parsed files alike;
the file format itself is :mod:`usar_replay.world.scenario_toml` (which imports this module).

All poses are in the ``map`` frame (REP-103: x east, y north, z up, yaw counter-clockwise from +x),
metres and radians.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, field

from usar_replay.core.errors import InvalidScenario

__all__ = [
    "Box",
    "Cylinder",
    "Sphere",
    "Marker",
    "RobotStart",
    "CameraSettings",
    "COURSE_CAMERA",
    "Scenario",
    "course_world",
    "WALL_THICKNESS",
    "WALL_HEIGHT",
    "building_extent",
    "check_ranges",
    "validate",
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
    """The explorer's RGB camera: image size, rate, horizontal FOV, encoding of recorded frames.

    ``pixel_fields_width``: the width of the camera whose pixels the detector's pixel-unit
    fields (``fiducial_area``, ``image_error``) are in; 0 means the images' own. The course's
    TurtleBot3 waffle camera in Gazebo is 1920x1080 at 30 Hz (:data:`COURSE_CAMERA`), which a
    CPU renderer cannot afford (bench/bench_record.py --camera: 6.6 times the recorder's CPU
    of 640x480 at 10 Hz, and 5 times the log; docs/ros1.md), while packages accept a detection
    on ``fiducial_area > 10000`` tuned on those images. So the course world renders a smaller
    image with the course's horizontal field of view, and the detector reports those two fields
    as the course's camera would measure them: at the same field of view a width ``W'`` has
    ``W'/W`` times the focal length, so areas scale by ``(W'/W)^2`` and reprojection errors by
    ``W'/W``. The images and their ``CameraInfo`` stay in the rendered image's pixels.

    With ``record.course_detection`` (the default) the detector goes further: it searches the
    course camera's own pixels (``pixel_fields_width`` wide, 16:9, this field of view) around
    the markers that can be in view, which the recorder renders and logs with each frame
    (:mod:`usar_replay.sim.course_view`), so the pose too is the course camera's, and the pixel
    fields need no scaling.
    """

    width: int = 640
    height: int = 480
    rate_hz: float = 10.0
    hfov: float = 1.3439
    encoding: str = "jpeg"
    pixel_fields_width: int = 0

    def pixel_scale(self) -> float:
        """How many of the pixel fields' pixels one rendered pixel spans (1.0: the same)."""
        return self.pixel_fields_width / self.width if self.pixel_fields_width else 1.0


COURSE_CAMERA = (1920, 1080, 30.0)
"""(width, height, rate in Hz) of the course's camera: the ``realsense_R200`` sensor of
turtlebot3_description's ``turtlebot3_waffle.gazebo.xacro`` (ROBOTIS-GIT/turtlebot3, melodic and
noetic branches: ``<horizontal_fov>1.3439``, ``<width>1920``, ``<height>1080``, the
``gazebo_ros_openni_kinect`` plugin's ``<updateRate>30.0``)."""


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
    world_key: str = ""
    """The digest of the world key a keyed variant was made with
    (:mod:`usar_replay.world.world_key`): with one, ``seed`` alone does not give this world."""
    assignment: str = "usar"
    """Which assignment this world is for: ``usar`` (the two-robot US&R mission) or
    ``ros2-final`` (the ROS 2 final project; :mod:`usar_replay.world.assignment`)."""
    task: tuple[tuple[str, float | str], ...] = ()
    """The assignment's own world data as flat ``dotted.key -> value`` pairs in key order (the
    file's ``[task]`` table; ``usar`` has none). :mod:`usar_replay.world.ros2_world` reads it."""

    def marker_by_id(self, marker_id: int) -> Marker:
        """The marker with this ID (KeyError if none)."""
        for m in self.markers:
            if m.id == marker_id:
                return m
        raise KeyError(marker_id)

    def summary(self) -> str:
        """A few lines for ``usar info`` and the record summary."""
        ids = ", ".join(str(m.id) for m in sorted(self.markers, key=lambda m: m.id))
        targets = "; ".join(f"({x:.3f}, {y:.3f})" for x, y in self.targets)
        cam = self.camera
        return "\n".join(
            [
                f"name {self.name}" + ("" if self.seed is None else f" (seed {self.seed})"),
                f"{len(self.walls)} walls, {len(self.boxes)} boxes, {len(self.cylinders)} "
                f"cylinders, {len(self.spheres)} spheres",
                f"markers {ids} ({self.markers[0].dictionary if self.markers else '-'})",
                f"targets {targets}",
                f"camera {cam.width}x{cam.height}@{cam.rate_hz:g} Hz {cam.encoding}"
                + (
                    f" (pixel fields as {cam.pixel_fields_width} px wide)"
                    if cam.pixel_fields_width
                    else ""
                )
                + ", "
                f"time limit {self.time_limit_s:g} s",
            ]
        )

    def parameters(self) -> dict[str, list[float]]:
        """The ROS parameters the mission reads: ``aruco_lookup_locations/target_k`` -> [x, y]."""
        return {
            f"aruco_lookup_locations/target_{i + 1}": [t[0], t[1]]
            for i, t in enumerate(self.targets)
        }


def wall(name: str, x: float, y: float, yaw: float, length: float) -> Box:
    """A standard wall (0.15 m thick, 1 m high) centred at (x, y), ``length`` along its yaw."""
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
        wall("west_outer", -5.033, 0.166, -pi / 2, 8.0),
        wall("east_outer", 8.567, 0.166, pi / 2, 8.0),
        wall("south_outer", 1.767, -3.759, 0.0, 13.75),
        wall("north_outer", 1.767, 4.091, pi, 13.75),
        wall("divider_west", -2.389, 0.037, -0.000773, 5.32209),
        wall("divider_east", 5.602, 0.059, 0.0, 6.0),
        wall("start_strip", -3.095, 1.930, 0.0, 4.0),
        wall("north_centre", 2.904, 1.462, pi, 4.0),
        wall("north_east", 4.829, 2.762, -pi / 2, 2.75),
        wall("diagonal_sw", 0.847, -1.091, -1.04726, 2.75),
        wall("diagonal_se", 4.675, -2.599, 1.0472, 2.75),
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
        camera=CameraSettings(pixel_fields_width=COURSE_CAMERA[0]),
    )


# --- what a world may hold ----------------------------------------------------------------------
#
# Errors name the field as the TOML file does (``markers[2].size: must be a positive number, got
# -0.1``) and stop at the first one: one line, what is wrong and where.

NAME_PATTERN = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,63}")
"""A scenario's ``name`` names its default recording (``recordings/NAME.mcap``), so it is a plain
file name: letters, digits, ``_ . -``, at most 64 characters, no ``..``, no path separator."""

RANGES: dict[str, tuple[float, float, str]] = {
    "coordinate": (-100.0, 100.0, "m"),
    "yaw": (-2 * math.pi, 2 * math.pi, "rad"),
    "wall.length": (0.01, 50.0, "m"),
    "wall.thickness": (0.01, 2.0, "m"),
    "wall.height": (0.05, 10.0, "m"),
    "box.z": (0.0, 10.0, "m"),
    "box.size": (0.01, 50.0, "m"),
    "cylinder.radius": (0.01, 10.0, "m"),
    "cylinder.height": (0.01, 10.0, "m"),
    "sphere.radius": (0.01, 10.0, "m"),
    "marker.z": (0.05, 2.0, "m"),
    "marker.size": (0.01, 1.0, "m"),
    "camera.width": (16, 4096, "px"),
    "camera.height": (16, 4096, "px"),
    "camera.rate_hz": (0.5, 60.0, "Hz"),
    "camera.hfov": (0.1, 3.0, "rad"),
    "camera.pixel_fields_width": (0, 8192, "px"),
    "time_limit_s": (1.0, 3600.0, "s"),
    "seed": (0, 2**32 - 1, ""),
}
"""Every number a scenario holds, with its range (inclusive) and unit: checked on load, listed
in docs/scenario.md. Coordinates are x, y of everything in ``map``."""

COUNTS: dict[str, tuple[int, int]] = {
    "walls": (1, 1000),
    "boxes": (0, 1000),
    "cylinders": (0, 1000),
    "spheres": (0, 1000),
    "markers": (1, 250),
    "aruco_lookup_locations": (1, 50),
}
"""How many of each a scenario may hold."""

DICTIONARIES: dict[str, int] = {
    f"DICT_{n}X{n}_{k}": k for n in (4, 5, 6, 7) for k in (50, 100, 250, 1000)
} | {"DICT_ARUCO_ORIGINAL": 1024}
"""ArUco dictionary names (OpenCV's) and how many marker IDs each holds."""


def field_error(source: str, path: str, problem: str) -> InvalidScenario:
    """The one-line error for a field, ``SOURCE: PATH: PROBLEM`` (the codec's too)."""
    return InvalidScenario(f"{source}: {path}: {problem}")


def _in_range(source: str, path: str, value: float, key: str) -> None:
    lo, hi, unit = RANGES[key]
    if not (lo <= value <= hi):
        u = f" {unit}" if unit else ""
        raise field_error(source, path, f"must be between {lo:g} and {hi:g}{u}, got {value!r}")


def check_count(source: str, path: str, n: int) -> None:
    """``n`` items of the list ``path`` (``walls``) are within :data:`COUNTS`."""
    lo, hi = COUNTS[path]
    if not (lo <= n <= hi):
        raise field_error(source, path, f"holds {n}; a scenario has {lo} to {hi}")


def _check_name(source: str, name: str) -> None:
    if not NAME_PATTERN.fullmatch(name) or ".." in name:
        raise field_error(
            source,
            "name",
            f"{name!r} is not a plain file name (it names recordings/NAME.mcap): use letters, "
            "digits, '_', '.', '-', at most 64 characters",
        )


def check_ranges(scn: Scenario, source: str = "scenario") -> None:
    """Every number within :data:`RANGES`, every list within :data:`COUNTS` (names in messages
    are the TOML file's: ``walls[3].length``)."""
    for key, n in (
        ("walls", len(scn.walls)),
        ("boxes", len(scn.boxes)),
        ("cylinders", len(scn.cylinders)),
        ("spheres", len(scn.spheres)),
        ("markers", len(scn.markers)),
        ("aruco_lookup_locations", len(scn.targets)),
    ):
        check_count(source, key, n)
    checks: list[tuple[str, float, str]] = []

    def xy(path: str, x: float, y: float) -> None:
        checks.extend([(f"{path}.x", x, "coordinate"), (f"{path}.y", y, "coordinate")])

    for i, w in enumerate(scn.walls):
        p = f"walls[{i}]"
        xy(p, w.x, w.y)
        checks += [
            (f"{p}.yaw", w.yaw, "yaw"),
            (f"{p}.length", w.size_x, "wall.length"),
            (f"{p}.thickness", w.size_y, "wall.thickness"),
            (f"{p}.height", w.size_z, "wall.height"),
        ]
    for i, b in enumerate(scn.boxes):
        p = f"boxes[{i}]"
        xy(p, b.x, b.y)
        checks += [(f"{p}.z", b.z, "box.z"), (f"{p}.yaw", b.yaw, "yaw")]
        checks += [(f"{p}.size_{a}", getattr(b, f"size_{a}"), "box.size") for a in "xyz"]
    for i, c in enumerate(scn.cylinders):
        p = f"cylinders[{i}]"
        xy(p, c.x, c.y)
        checks += [(f"{p}.radius", c.radius, "cylinder.radius")]
        checks += [(f"{p}.height", c.height, "cylinder.height")]
    for i, sp in enumerate(scn.spheres):
        xy(f"spheres[{i}]", sp.x, sp.y)
        checks.append((f"spheres[{i}].radius", sp.radius, "sphere.radius"))
    for i, m in enumerate(scn.markers):
        p = f"markers[{i}]"
        xy(p, m.x, m.y)
        checks += [(f"{p}.z", m.z, "marker.z"), (f"{p}.yaw", m.yaw, "yaw")]
        checks.append((f"{p}.size", m.size, "marker.size"))
    for i, (tx, ty) in enumerate(scn.targets):
        xy(f"aruco_lookup_locations.target_{i + 1}", tx, ty)
    for r in (scn.explorer, scn.follower):
        xy(f"robots.{r.name}", r.x, r.y)
        checks.append((f"robots.{r.name}.yaw", r.yaw, "yaw"))
    cam = scn.camera
    checks += [
        ("camera.width", cam.width, "camera.width"),
        ("camera.height", cam.height, "camera.height"),
        ("camera.rate_hz", cam.rate_hz, "camera.rate_hz"),
        ("camera.hfov", cam.hfov, "camera.hfov"),
        ("camera.pixel_fields_width", cam.pixel_fields_width, "camera.pixel_fields_width"),
        ("time_limit_s", scn.time_limit_s, "time_limit_s"),
    ]
    if scn.seed is not None:
        checks.append(("seed", scn.seed, "seed"))
    for path, value, key in checks:
        if not math.isfinite(value):
            raise field_error(source, path, f"must be finite, got {value!r}")
        _in_range(source, path, value, key)


def validate(scn: Scenario, source: str = "scenario") -> None:
    """Semantic checks that hold for constructed values too (not only parsed files)."""
    _check_name(source, scn.name)
    if not scn.walls:
        raise field_error(source, "walls", "at least one wall is needed")
    if not scn.targets:
        raise field_error(source, "aruco_lookup_locations", "at least one target is needed")
    check_ranges(scn, source)
    seen: dict[int, int] = {}
    for i, m in enumerate(scn.markers):
        if m.id in seen:
            raise field_error(
                source,
                f"markers[{i}].id",
                f"duplicate marker id {m.id} (also markers[{seen[m.id]}])",
            )
        seen[m.id] = i
    x0, y0, x1, y1 = building_extent(scn)
    points = [(f"aruco_lookup_locations.target_{i + 1}", t) for i, t in enumerate(scn.targets)]
    if scn.assignment == "usar":  # other assignments place their robots in [task]
        points += [(f"robots.{r.name}", (r.x, r.y)) for r in (scn.explorer, scn.follower)]
    for path, (x, y) in points:
        if not (x0 <= x <= x1 and y0 <= y <= y1):
            raise field_error(
                source,
                path,
                f"({x}, {y}) is outside the building (x {x0:.2f}..{x1:.2f}, y {y0:.2f}..{y1:.2f})",
            )


def building_extent(scn: Scenario) -> tuple[float, float, float, float]:
    """(xmin, ymin, xmax, ymax) of the walls' footprints."""
    xs: list[float] = []
    ys: list[float] = []
    for w in scn.walls:
        c, s = math.cos(w.yaw), math.sin(w.yaw)
        for dx, dy in ((1, 1), (1, -1), (-1, 1), (-1, -1)):
            lx, ly = dx * w.size_x / 2, dy * w.size_y / 2
            xs.append(w.x + c * lx - s * ly)
            ys.append(w.y + s * lx + c * ly)
    return min(xs), min(ys), max(xs), max(ys)


def close_matches(word: str, choices: Sequence[str]) -> list[str]:
    """The nearest of ``choices`` to a misspelt ``word`` (difflib, imported only when a
    scenario has a mistake: loading a good one never needs it)."""
    import difflib

    return difflib.get_close_matches(word, choices, n=1)
