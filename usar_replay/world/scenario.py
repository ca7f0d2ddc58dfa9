"""The world as data: walls, obstacles, markers, lookup targets, robot starts, camera, time limit.

Pure data, no I/O beyond TOML text: the simulator builds from it, the navigator grids it, the
mission reads its parameters, and the log carries it so a recording is self-contained.
The course world of ENPM809Y (``../shared/course-world.md``) is :func:`course_world`.

All poses are in the ``map`` frame (REP-103: x east, y north, z up, yaw counter-clockwise from +x),
metres and radians.
"""

from __future__ import annotations

import math
import os
import re
import tomllib
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from usar_replay.core.errors import InvalidScenario

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
    encoding: str = "jpeg"


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
    ``ros2-final`` (the ROS 2 final project; :mod:`usar_replay.grading.assignment`)."""
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
                f"camera {cam.width}x{cam.height}@{cam.rate_hz:g} Hz {cam.encoding}, "
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
    )


# --- TOML ---------------------------------------------------------------------------------------
#
# The file format, meant to be edited by hand (an instructor's "different environment"):
#
#   format_version = 1
#   name = "course"
#   time_limit_s = 600.0
#   seed = 3                      # optional: the variant seed this world came from
#   world_key = "0123abcd..."     # optional: digest of the world key of a keyed variant
#   [camera]        width, height, rate_hz, hfov, encoding ("png" | "jpeg")
#   [robots.explorer] / [robots.follower]   x, y, yaw
#   [aruco_lookup_locations]      target_1 = [x, y], target_2 = [x, y], ... (as the course's
#                                 ROS parameter file names them)
#   [[walls]]      name, x, y, yaw, length, optional thickness (0.15) and height (1.0)
#   [[boxes]]      name, x, y, z, size_x, size_y, size_z, yaw
#   [[cylinders]]  name, x, y, radius, height
#   [[spheres]]    name, x, y, radius
#   [[markers]]    id, x, y, z, yaw, size, dictionary
#
# Errors name the field (``markers[2].size: must be a positive number, got -0.1``) and stop at the
# first one: one line, what is wrong and where.

FORMAT_VERSION = 1

MAX_FILE_BYTES = 1 << 20
"""A scenario file is at most 1 MiB (the course world is 4 KiB); a bigger one is refused before
it is parsed, so a 50 MB file cannot tie up ``--check`` for minutes."""

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


def _err(source: str, path: str, problem: str) -> InvalidScenario:
    return InvalidScenario(f"{source}: {path}: {problem}")


def _in_range(source: str, path: str, value: float, key: str) -> None:
    lo, hi, unit = RANGES[key]
    if not (lo <= value <= hi):
        u = f" {unit}" if unit else ""
        raise _err(source, path, f"must be between {lo:g} and {hi:g}{u}, got {value!r}")


def _check_count(source: str, path: str, n: int) -> None:
    lo, hi = COUNTS[path]
    if not (lo <= n <= hi):
        raise _err(source, path, f"holds {n}; a scenario has {lo} to {hi}")


def _check_keys(
    source: str, path: str, table: dict[str, Any], allowed: list[str], required: list[str]
) -> None:
    for key in table:
        if key not in allowed:
            close = _close_matches(key, allowed)
            hint = f" (did you mean '{close[0]}'?)" if close else f" (known: {', '.join(allowed)})"
            raise _err(source, f"{path}.{key}" if path else key, "unknown field" + hint)
    for key in required:
        if key not in table:
            raise _err(source, path or "scenario", f"missing field '{key}'")


def _num(source: str, path: str, value: Any, *, positive: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise _err(source, path, f"must be a number, got {value!r}")
    v = float(value)
    if not math.isfinite(v):
        raise _err(source, path, f"must be finite, got {value!r}")
    if positive and v <= 0:
        raise _err(source, path, f"must be a positive number, got {value!r}")
    return v


def _int(source: str, path: str, value: Any, *, minimum: int = 0) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise _err(source, path, f"must be an integer, got {value!r}")
    if value < minimum:
        raise _err(source, path, f"must be >= {minimum}, got {value!r}")
    return value


def _str(source: str, path: str, value: Any) -> str:
    if not isinstance(value, str) or not value:
        raise _err(source, path, f"must be a non-empty string, got {value!r}")
    return value


def _list(source: str, path: str, value: Any) -> list[dict[str, Any]]:
    if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
        raise _err(source, path, "must be an array of tables ([[...]])")
    _check_count(source, path, len(value))  # before parsing: a huge count is refused at once
    return value


def _parsewall(src: str, path: str, t: dict[str, Any]) -> Box:
    _check_keys(
        src,
        path,
        t,
        ["name", "x", "y", "yaw", "length", "thickness", "height"],
        ["name", "x", "y", "yaw", "length"],
    )
    height = _num(src, f"{path}.height", t.get("height", WALL_HEIGHT), positive=True)
    return Box(
        name=_str(src, f"{path}.name", t["name"]),
        x=_num(src, f"{path}.x", t["x"]),
        y=_num(src, f"{path}.y", t["y"]),
        z=height / 2,
        size_x=_num(src, f"{path}.length", t["length"], positive=True),
        size_y=_num(src, f"{path}.thickness", t.get("thickness", WALL_THICKNESS), positive=True),
        size_z=height,
        yaw=_num(src, f"{path}.yaw", t["yaw"]),
    )


def _parse_box(src: str, path: str, t: dict[str, Any]) -> Box:
    keys = ["name", "x", "y", "z", "size_x", "size_y", "size_z", "yaw"]
    _check_keys(src, path, t, keys, keys[:7])
    return Box(
        name=_str(src, f"{path}.name", t["name"]),
        x=_num(src, f"{path}.x", t["x"]),
        y=_num(src, f"{path}.y", t["y"]),
        z=_num(src, f"{path}.z", t["z"]),
        size_x=_num(src, f"{path}.size_x", t["size_x"], positive=True),
        size_y=_num(src, f"{path}.size_y", t["size_y"], positive=True),
        size_z=_num(src, f"{path}.size_z", t["size_z"], positive=True),
        yaw=_num(src, f"{path}.yaw", t.get("yaw", 0.0)),
    )


def _parse_marker(src: str, path: str, t: dict[str, Any]) -> Marker:
    keys = ["id", "x", "y", "z", "yaw", "size", "dictionary"]
    _check_keys(src, path, t, keys, ["id", "x", "y", "yaw"])
    dictionary = _str(src, f"{path}.dictionary", t.get("dictionary", "DICT_4X4_50"))
    if dictionary not in DICTIONARIES:
        close = _close_matches(dictionary, list(DICTIONARIES))
        hint = f" (did you mean '{close[0]}'?)" if close else ""
        raise _err(src, f"{path}.dictionary", f"unknown ArUco dictionary {dictionary!r}{hint}")
    mid = _int(src, f"{path}.id", t["id"])
    if mid >= DICTIONARIES[dictionary]:
        raise _err(
            src, f"{path}.id", f"{mid} is outside {dictionary} (0..{DICTIONARIES[dictionary] - 1})"
        )
    return Marker(
        id=mid,
        x=_num(src, f"{path}.x", t["x"]),
        y=_num(src, f"{path}.y", t["y"]),
        z=_num(src, f"{path}.z", t.get("z", 0.2), positive=True),
        yaw=_num(src, f"{path}.yaw", t["yaw"]),
        size=_num(src, f"{path}.size", t.get("size", 0.15), positive=True),
        dictionary=dictionary,
    )


def _parse_xy(src: str, path: str, value: Any) -> tuple[float, float]:
    if not isinstance(value, list) or len(value) != 2:
        raise _err(src, path, f"must be [x, y], got {value!r}")
    return (_num(src, f"{path}[0]", value[0]), _num(src, f"{path}[1]", value[1]))


def from_toml(text: str, source: str = "<string>") -> Scenario:
    """Parse and validate a scenario; :class:`InvalidScenario` names the first bad field."""
    if len(text) > MAX_FILE_BYTES:
        raise InvalidScenario(
            f"{source}: the file holds {len(text)} characters; a scenario is at most "
            f"{MAX_FILE_BYTES} (1 MiB)"
        )
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise InvalidScenario(f"{source}: invalid TOML: {err}") from err
    src = source
    top = [
        "format_version",
        "name",
        "time_limit_s",
        "seed",
        "world_key",
        "camera",
        "robots",
        "aruco_lookup_locations",
        "walls",
        "boxes",
        "cylinders",
        "spheres",
        "markers",
        "assignment",
        "task",
    ]
    _check_keys(src, "", data, top, ["name", "walls", "markers", "aruco_lookup_locations"])
    version = data.get("format_version", FORMAT_VERSION)
    if version != FORMAT_VERSION:
        raise _err(
            src,
            "format_version",
            f"this usar-replay reads version {FORMAT_VERSION}, got {version!r}",
        )
    cam_t = data.get("camera", {})
    if not isinstance(cam_t, dict):
        raise _err(src, "camera", "must be a table")
    _check_keys(src, "camera", cam_t, ["width", "height", "rate_hz", "hfov", "encoding"], [])
    d = CameraSettings()
    hfov = _num(src, "camera.hfov", cam_t.get("hfov", d.hfov), positive=True)
    if hfov >= math.pi:
        raise _err(src, "camera.hfov", f"must be below pi radians, got {hfov!r}")
    encoding = cam_t.get("encoding", d.encoding)
    if encoding not in ("png", "jpeg"):
        raise _err(src, "camera.encoding", f"must be 'png' or 'jpeg', got {encoding!r}")
    camera = CameraSettings(
        width=_int(src, "camera.width", cam_t.get("width", d.width), minimum=16),
        height=_int(src, "camera.height", cam_t.get("height", d.height), minimum=16),
        rate_hz=_num(src, "camera.rate_hz", cam_t.get("rate_hz", d.rate_hz), positive=True),
        hfov=hfov,
        encoding=encoding,
    )
    robots_t = data.get("robots", {})
    if not isinstance(robots_t, dict):
        raise _err(src, "robots", "must be a table with [robots.explorer] and [robots.follower]")
    _check_keys(src, "robots", robots_t, ["explorer", "follower"], [])
    starts = {
        "explorer": RobotStart(name="explorer", x=-4.0, y=2.5),
        "follower": RobotStart(name="follower", x=-4.0, y=3.5),
    }
    for name, table in robots_t.items():
        path = f"robots.{name}"
        if not isinstance(table, dict):
            raise _err(src, path, "must be a table with x, y, yaw")
        _check_keys(src, path, table, ["x", "y", "yaw"], ["x", "y"])
        starts[name] = RobotStart(
            name=name,
            x=_num(src, f"{path}.x", table["x"]),
            y=_num(src, f"{path}.y", table["y"]),
            yaw=_num(src, f"{path}.yaw", table.get("yaw", 0.0)),
        )
    loc = data["aruco_lookup_locations"]
    if not isinstance(loc, dict) or not loc:
        raise _err(src, "aruco_lookup_locations", "must be a table of target_1 = [x, y], ...")
    _check_count(src, "aruco_lookup_locations", len(loc))
    for key in loc:
        if not (key.startswith("target_") and key[7:].isdigit() and int(key[7:]) >= 1):
            raise _err(src, f"aruco_lookup_locations.{key}", "unknown field (expected target_N)")
    targets = []
    for i in range(1, len(loc) + 1):
        key = f"target_{i}"
        if key not in loc:
            raise _err(
                src,
                "aruco_lookup_locations",
                f"expected target_1..target_{len(loc)} without gaps, missing {key}",
            )
        targets.append(_parse_xy(src, f"aruco_lookup_locations.{key}", loc[key]))
    scn = Scenario(
        name=_str(src, "name", data["name"]),
        walls=tuple(
            _parsewall(src, f"walls[{i}]", t)
            for i, t in enumerate(_list(src, "walls", data["walls"]))
        ),
        boxes=tuple(
            _parse_box(src, f"boxes[{i}]", t)
            for i, t in enumerate(_list(src, "boxes", data.get("boxes", [])))
        ),
        cylinders=tuple(
            _parse_cylinder(src, f"cylinders[{i}]", t)
            for i, t in enumerate(_list(src, "cylinders", data.get("cylinders", [])))
        ),
        spheres=tuple(
            _parse_sphere(src, f"spheres[{i}]", t)
            for i, t in enumerate(_list(src, "spheres", data.get("spheres", [])))
        ),
        markers=tuple(
            _parse_marker(src, f"markers[{i}]", t)
            for i, t in enumerate(_list(src, "markers", data["markers"]))
        ),
        targets=tuple(targets),
        explorer=starts["explorer"],
        follower=starts["follower"],
        camera=camera,
        time_limit_s=_num(src, "time_limit_s", data.get("time_limit_s", 600.0), positive=True),
        seed=None if data.get("seed") is None else _int(src, "seed", data["seed"]),
        world_key=_str(src, "world_key", data["world_key"]) if "world_key" in data else "",
        assignment=_str(src, "assignment", data.get("assignment", "usar")),
        task=_parse_task(src, data.get("task", {})),
    )
    validate(scn, src)
    return scn


ASSIGNMENTS = ("usar", "ros2-final")
"""The assignments a scenario may name (``assignment = "..."``)."""


def _parse_task(src: str, table: Any, prefix: str = "task") -> tuple[tuple[str, float | str], ...]:
    """The ``[task]`` table flattened to sorted ``dotted.key -> number | string`` pairs."""
    if not isinstance(table, dict):
        raise _err(src, prefix, "must be a table")
    out: list[tuple[str, float | str]] = []
    for key, value in table.items():
        path = f"{prefix}.{key}"
        if isinstance(value, dict):
            out += [(f"{key}.{k}", v) for k, v in _parse_task(src, value, path)]
        elif isinstance(value, str):
            out.append((key, value))
        else:
            out.append((key, _num(src, path, value)))
    return tuple(sorted(out))


def _unflatten(pairs: tuple[tuple[str, float | str], ...]) -> dict[str, Any]:
    root: dict[str, Any] = {}
    for key, value in pairs:
        *parents, leaf = key.split(".")
        node = root
        for part in parents:
            node = node.setdefault(part, {})
        node[leaf] = value
    return root


def _parse_cylinder(src: str, path: str, t: dict[str, Any]) -> Cylinder:
    _check_keys(
        src, path, t, ["name", "x", "y", "radius", "height"], ["name", "x", "y", "radius", "height"]
    )
    return Cylinder(
        name=_str(src, f"{path}.name", t["name"]),
        x=_num(src, f"{path}.x", t["x"]),
        y=_num(src, f"{path}.y", t["y"]),
        radius=_num(src, f"{path}.radius", t["radius"], positive=True),
        height=_num(src, f"{path}.height", t["height"], positive=True),
    )


def _parse_sphere(src: str, path: str, t: dict[str, Any]) -> Sphere:
    _check_keys(src, path, t, ["name", "x", "y", "radius"], ["name", "x", "y", "radius"])
    return Sphere(
        name=_str(src, f"{path}.name", t["name"]),
        x=_num(src, f"{path}.x", t["x"]),
        y=_num(src, f"{path}.y", t["y"]),
        radius=_num(src, f"{path}.radius", t["radius"], positive=True),
    )


def _check_name(source: str, name: str) -> None:
    if not NAME_PATTERN.fullmatch(name) or ".." in name:
        raise _err(
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
        _check_count(source, key, n)
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
        ("time_limit_s", scn.time_limit_s, "time_limit_s"),
    ]
    if scn.seed is not None:
        checks.append(("seed", scn.seed, "seed"))
    for path, value, key in checks:
        if not math.isfinite(value):
            raise _err(source, path, f"must be finite, got {value!r}")
        _in_range(source, path, value, key)


def validate(scn: Scenario, source: str = "scenario") -> None:
    """Semantic checks that hold for constructed values too (not only parsed files)."""
    _check_name(source, scn.name)
    if not scn.walls:
        raise _err(source, "walls", "at least one wall is needed")
    if not scn.targets:
        raise _err(source, "aruco_lookup_locations", "at least one target is needed")
    if scn.assignment not in ASSIGNMENTS:
        close = _close_matches(scn.assignment, ASSIGNMENTS)
        hint = f" (did you mean '{close[0]}'?)" if close else f" (known: {', '.join(ASSIGNMENTS)})"
        raise _err(source, "assignment", f"unknown assignment {scn.assignment!r}{hint}")
    check_ranges(scn, source)
    seen: dict[int, int] = {}
    for i, m in enumerate(scn.markers):
        if m.id in seen:
            raise _err(
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
            raise _err(
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


def to_toml(scn: Scenario) -> str:
    """The scenario as TOML text; ``from_toml(to_toml(s)) == s`` exactly (floats by repr)."""
    data: dict[str, Any] = {
        "format_version": FORMAT_VERSION,
        "name": scn.name,
        "time_limit_s": scn.time_limit_s,
    }
    if scn.seed is not None:
        data["seed"] = scn.seed
    if scn.world_key:
        data["world_key"] = scn.world_key
    if scn.assignment != "usar":
        data["assignment"] = scn.assignment
    cam = scn.camera
    data["camera"] = {
        "width": cam.width,
        "height": cam.height,
        "rate_hz": cam.rate_hz,
        "hfov": cam.hfov,
        "encoding": cam.encoding,
    }
    if scn.assignment == "usar":
        data["robots"] = {
            r.name: {"x": r.x, "y": r.y, "yaw": r.yaw} for r in (scn.explorer, scn.follower)
        }
    if scn.task:
        data["task"] = _unflatten(scn.task)
    data["aruco_lookup_locations"] = {
        f"target_{i + 1}": [t[0], t[1]] for i, t in enumerate(scn.targets)
    }
    data["walls"] = []
    for w in scn.walls:
        wall: dict[str, Any] = {
            "name": w.name,
            "x": w.x,
            "y": w.y,
            "yaw": w.yaw,
            "length": w.size_x,
        }
        if w.size_y != WALL_THICKNESS:
            wall["thickness"] = w.size_y
        if w.size_z != WALL_HEIGHT or w.z != w.size_z / 2:
            wall["height"] = w.size_z
        data["walls"].append(wall)
    data["boxes"] = [
        {
            "name": b.name,
            "x": b.x,
            "y": b.y,
            "z": b.z,
            "size_x": b.size_x,
            "size_y": b.size_y,
            "size_z": b.size_z,
            "yaw": b.yaw,
        }
        for b in scn.boxes
    ]
    data["cylinders"] = [
        {"name": c.name, "x": c.x, "y": c.y, "radius": c.radius, "height": c.height}
        for c in scn.cylinders
    ]
    data["spheres"] = [
        {"name": s.name, "x": s.x, "y": s.y, "radius": s.radius} for s in scn.spheres
    ]
    data["markers"] = [
        {
            "id": m.id,
            "x": m.x,
            "y": m.y,
            "z": m.z,
            "yaw": m.yaw,
            "size": m.size,
            "dictionary": m.dictionary,
        }
        for m in scn.markers
    ]
    import tomli_w  # deferred: loading a world (every command) never writes TOML

    # tomli_w splits every array over lines; keep [x, y] pairs on one line for people
    text = re.sub(r"\[\n\s+([^,\n]+),\n\s+([^,\n]+),\n\]", r"[\1, \2]", tomli_w.dumps(data))
    return _commented(text)


_HEADER = """\
# A usar-replay scenario: the world and the mission's parameters (docs/scenario.md).
# Units: metres, radians (yaw counter-clockwise from +x, map frame: x east, y north), seconds.
# Every number has a range checked on load; `usar scenario --scenario FILE --check` checks
# that the world can be completed.
"""

_LINE_COMMENTS: dict[tuple[str, str], str] = {
    ("", "format_version"): "file format (this usar-replay reads 1)",
    ("", "name"): "names the default output recordings/NAME.mcap: letters, digits, _ . -",
    ("", "time_limit_s"): "s, the mission's time limit (1..3600)",
    ("", "seed"): "the variant seed this world came from",
    ("", "world_key"): "digest of the secret key of a hidden variant (see docs/batch.md)",
    ("", "walls"): "x, y: centre (m); yaw (rad); length (m, 0.01..50); thickness (m, 0.15); "
    "height (m, 1)",
    ("", "boxes"): "x, y, z: centre (m); size_x, size_y, size_z (m, 0.01..50); yaw (rad)",
    ("", "cylinders"): "x, y: centre (m); radius (m, 0.01..10); height (m, 0.01..10)",
    ("", "spheres"): "x, y: centre (m); radius (m, 0.01..10), resting on the floor",
    ("", "markers"): "x, y, z: face centre (m, z 0.05..2); yaw (rad): the face looks along +x; "
    "size (m)",
    ("camera", "width"): "px (16..4096)",
    ("camera", "height"): "px (16..4096)",
    ("camera", "rate_hz"): "Hz, frames per second (0.5..60)",
    ("camera", "hfov"): "rad, horizontal field of view (0.1..3.0)",
    ("camera", "encoding"): "recorded frames: png (lossless) or jpeg",
    ("robots", "x"): "m",
    ("robots", "y"): "m",
    ("robots", "yaw"): "rad",
    ("aruco_lookup_locations", ""): "target_N = [x, y] in m, visited in order",
}


def _commented(text: str) -> str:
    """``text`` with a header and a comment with units on each key (TOML ignores them)."""
    out = [_HEADER]
    section = ""
    for line in text.splitlines():
        stripped = line.strip()
        if stripped.startswith("["):
            section = stripped.strip("[]").split(".")[0]
            out.append(line)
            note = _LINE_COMMENTS.get((section, ""))
            if note:
                out.append(f"# {note}")
            continue
        key = line.split(" = ", 1)[0] if " = " in line and not line.startswith(" ") else ""
        note = _LINE_COMMENTS.get((section, key)) if key else None
        if note and section == "" and key in ("walls", "boxes", "cylinders", "spheres", "markers"):
            out.append(f"# {key}: {note}")
            out.append(line)
        elif note:
            out.append(f"{line}  # {note}")
        else:
            out.append(line)
    return "\n".join(out) + "\n"


def load(path: str | os.PathLike[str]) -> Scenario:
    """Read a scenario file (a missing file is an :class:`InvalidScenario` too)."""
    try:
        size = Path(path).stat().st_size
        if size > MAX_FILE_BYTES:
            raise InvalidScenario(
                f"{path}: the file is {size} bytes; a scenario is at most {MAX_FILE_BYTES} (1 MiB)"
            )
        text = Path(path).read_text(encoding="utf-8")
    except FileNotFoundError as err:
        raise InvalidScenario(f"{path}: no such scenario file") from err
    except (OSError, UnicodeDecodeError) as err:
        raise InvalidScenario(f"{path}: cannot read the scenario: {err}") from err
    return from_toml(text, source=str(path))


def save(scn: Scenario, path: str | os.PathLike[str], *, overwrite: bool = False) -> None:
    """Write ``scn`` as TOML, atomically (never a half-written or 0-byte file)."""
    from usar_replay.core.outfiles import write_text

    write_text(path, to_toml(scn), overwrite=overwrite)


def _close_matches(word: str, choices: Sequence[str]) -> list[str]:
    """The nearest of ``choices`` to a misspelt ``word`` (difflib, imported only when a
    scenario has a mistake: loading a good one never needs it)."""
    import difflib

    return difflib.get_close_matches(word, choices, n=1)
