"""The scenario's TOML file: :func:`from_toml`, :func:`to_toml`, :func:`load`, :func:`save`.

Why apart from :mod:`usar_replay.world.scenario`: the model (the dataclasses, the course world,
the range and semantic checks) is what the simulator, the planner and the rubrics need; the file
format (field names, defaults, the order of keys, comments for people, error paths such as
``walls[3].length``) is only for reading and writing files and log attachments. The codec imports
the model, never the reverse: :func:`from_toml` checks each field's type as it parses, then runs
the model's own :func:`usar_replay.world.scenario.validate`, so a parsed world and a constructed
one are held to the same rules.

:func:`to_toml` writes keys in a fixed order, floats by ``repr``: the text is attached to every
recording, so the same world gives the same log bytes, and ``from_toml(to_toml(s)) == s``.
"""

from __future__ import annotations

import math
import os
import re
import tomllib
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

from usar_replay.core.errors import InvalidScenario
from usar_replay.world.assignment import check_known
from usar_replay.world.scenario import (
    DICTIONARIES,
    WALL_HEIGHT,
    WALL_THICKNESS,
    Box,
    CameraSettings,
    Cylinder,
    Marker,
    RobotStart,
    Scenario,
    Sphere,
    check_count,
    close_matches,
    field_error,
    validate,
)

__all__ = ["FORMAT_VERSION", "MAX_FILE_BYTES", "from_toml", "load", "save", "to_toml"]

_T = TypeVar("_T")

# --- the file -------------------------------------------------------------------------------------
#
# The file format, meant to be edited by hand (an instructor's "different environment"):
#
#   format_version = 1
#   name = "course"
#   time_limit_s = 600.0
#   seed = 3                      # optional: the variant seed this world came from
#   world_key = "0123abcd..."     # optional: digest of the world key of a hidden variant
#   [camera]        width, height, rate_hz, hfov, encoding ("png" | "jpeg"),
#                   pixel_fields_width (0: the images' own)
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


def from_toml(text: str, source: str = "<string>") -> Scenario:
    """Parse and validate a scenario; :class:`InvalidScenario` names the first bad field."""
    src = source
    data = _read_toml(text, src)
    _check_top_level(src, data)
    # the phases in the order errors are reported: the first bad field is the one named
    camera = _parse_camera(src, data.get("camera", {}))
    starts = _parse_robots(src, data.get("robots", {}))
    targets = _parse_targets(src, data["aruco_lookup_locations"])
    scn = Scenario(
        name=_str(src, "name", data["name"]),
        walls=_parse_all(src, "walls", data["walls"], _parsewall),
        boxes=_parse_all(src, "boxes", data.get("boxes", []), _parse_box),
        cylinders=_parse_all(src, "cylinders", data.get("cylinders", []), _parse_cylinder),
        spheres=_parse_all(src, "spheres", data.get("spheres", []), _parse_sphere),
        markers=_parse_all(src, "markers", data["markers"], _parse_marker),
        targets=targets,
        explorer=starts["explorer"],
        follower=starts["follower"],
        camera=camera,
        time_limit_s=_num(src, "time_limit_s", data.get("time_limit_s", 600.0), positive=True),
        seed=None if data.get("seed") is None else _int(src, "seed", data["seed"]),
        world_key=_str(src, "world_key", data["world_key"]) if "world_key" in data else "",
        assignment=_str(src, "assignment", data.get("assignment", "usar")),
        task=_parse_task(src, data.get("task", {})),
    )
    check_known(scn.assignment, src)  # the registry (built-in or a package's entry point)
    validate(scn, src)
    return scn


def _read_toml(text: str, src: str) -> dict[str, Any]:
    """The file's tables, once its size is known to be sane and its TOML to parse."""
    if len(text) > MAX_FILE_BYTES:
        raise InvalidScenario(
            f"{src}: the file holds {len(text)} characters; a scenario is at most "
            f"{MAX_FILE_BYTES} (1 MiB)"
        )
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise InvalidScenario(f"{src}: invalid TOML: {err}") from err
    except RecursionError:  # a log's attachment is anyone's: arrays nested thousands deep
        raise InvalidScenario(f"{src}: invalid TOML: nested too deep") from None


_TOP_LEVEL = [
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


def _check_top_level(src: str, data: dict[str, Any]) -> None:
    """Only known top-level keys, the required ones, and a format version this code reads."""
    _check_keys(src, "", data, _TOP_LEVEL, ["name", "walls", "markers", "aruco_lookup_locations"])
    version = data.get("format_version", FORMAT_VERSION)
    if version != FORMAT_VERSION:
        raise field_error(
            src,
            "format_version",
            f"this usar-replay reads version {FORMAT_VERSION}, got {version!r}",
        )


def _parse_camera(src: str, cam_t: Any) -> CameraSettings:
    """``[camera]``: each field defaults to :class:`CameraSettings`'s."""
    if not isinstance(cam_t, dict):
        raise field_error(src, "camera", "must be a table")
    _check_keys(
        src,
        "camera",
        cam_t,
        ["width", "height", "rate_hz", "hfov", "encoding", "pixel_fields_width"],
        [],
    )
    d = CameraSettings()
    hfov = _num(src, "camera.hfov", cam_t.get("hfov", d.hfov), positive=True)
    if hfov >= math.pi:
        raise field_error(src, "camera.hfov", f"must be below pi radians, got {hfov!r}")
    encoding = cam_t.get("encoding", d.encoding)
    if encoding not in ("png", "jpeg"):
        raise field_error(src, "camera.encoding", f"must be 'png' or 'jpeg', got {encoding!r}")
    return CameraSettings(
        width=_int(src, "camera.width", cam_t.get("width", d.width), minimum=16),
        height=_int(src, "camera.height", cam_t.get("height", d.height), minimum=16),
        rate_hz=_num(src, "camera.rate_hz", cam_t.get("rate_hz", d.rate_hz), positive=True),
        hfov=hfov,
        encoding=encoding,
        pixel_fields_width=_int(
            src,
            "camera.pixel_fields_width",
            cam_t.get("pixel_fields_width", d.pixel_fields_width),
            minimum=0,
        ),
    )


def _parse_robots(src: str, robots_t: Any) -> dict[str, RobotStart]:
    """``[robots.explorer]`` and ``[robots.follower]`` as the ``explorer`` and ``follower``
    fields of the scenario (a robot not in the file keeps its default start)."""
    if not isinstance(robots_t, dict):
        raise field_error(
            src, "robots", "must be a table with [robots.explorer] and [robots.follower]"
        )
    _check_keys(src, "robots", robots_t, ["explorer", "follower"], [])
    starts = {
        "explorer": RobotStart(name="explorer", x=-4.0, y=2.5),
        "follower": RobotStart(name="follower", x=-4.0, y=3.5),
    }
    for name, table in robots_t.items():
        path = f"robots.{name}"
        if not isinstance(table, dict):
            raise field_error(src, path, "must be a table with x, y, yaw")
        _check_keys(src, path, table, ["x", "y", "yaw"], ["x", "y"])
        starts[name] = RobotStart(
            name=name,
            x=_num(src, f"{path}.x", table["x"]),
            y=_num(src, f"{path}.y", table["y"]),
            yaw=_num(src, f"{path}.yaw", table.get("yaw", 0.0)),
        )
    return starts


def _parse_targets(src: str, loc: Any) -> tuple[tuple[float, float], ...]:
    """``[aruco_lookup_locations]``: ``target_1 .. target_N`` without gaps, in that order."""
    if not isinstance(loc, dict) or not loc:
        raise field_error(
            src, "aruco_lookup_locations", "must be a table of target_1 = [x, y], ..."
        )
    check_count(src, "aruco_lookup_locations", len(loc))
    for key in loc:
        if not (key.startswith("target_") and key[7:].isdigit() and int(key[7:]) >= 1):
            raise field_error(
                src, f"aruco_lookup_locations.{key}", "unknown field (expected target_N)"
            )
    targets = []
    for i in range(1, len(loc) + 1):
        key = f"target_{i}"
        if key not in loc:
            raise field_error(
                src,
                "aruco_lookup_locations",
                f"expected target_1..target_{len(loc)} without gaps, missing {key}",
            )
        targets.append(_parse_xy(src, f"aruco_lookup_locations.{key}", loc[key]))
    return tuple(targets)


def _parse_all(
    src: str, key: str, value: Any, parse: Callable[[str, str, dict[str, Any]], _T]
) -> tuple[_T, ...]:
    """An array of tables (``[[walls]]``), each parsed with its path (``walls[3]``)."""
    return tuple(parse(src, f"{key}[{i}]", t) for i, t in enumerate(_list(src, key, value)))


# --- one field, one table ------------------------------------------------------------------------


def _check_keys(
    source: str, path: str, table: dict[str, Any], allowed: list[str], required: list[str]
) -> None:
    for key in table:
        if key not in allowed:
            close = close_matches(key, allowed)
            hint = f" (did you mean '{close[0]}'?)" if close else f" (known: {', '.join(allowed)})"
            raise field_error(source, f"{path}.{key}" if path else key, "unknown field" + hint)
    for key in required:
        if key not in table:
            raise field_error(source, path or "scenario", f"missing field '{key}'")


def _num(source: str, path: str, value: Any, *, positive: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise field_error(source, path, f"must be a number, got {value!r}")
    v = float(value)
    if not math.isfinite(v):
        raise field_error(source, path, f"must be finite, got {value!r}")
    if positive and v <= 0:
        raise field_error(source, path, f"must be a positive number, got {value!r}")
    return v


def _int(source: str, path: str, value: Any, *, minimum: int = 0) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise field_error(source, path, f"must be an integer, got {value!r}")
    if value < minimum:
        raise field_error(source, path, f"must be >= {minimum}, got {value!r}")
    return value


def _str(source: str, path: str, value: Any) -> str:
    if not isinstance(value, str) or not value:
        raise field_error(source, path, f"must be a non-empty string, got {value!r}")
    return value


def _list(source: str, path: str, value: Any) -> list[dict[str, Any]]:
    if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
        raise field_error(source, path, "must be an array of tables ([[...]])")
    check_count(source, path, len(value))  # before parsing: a huge count is refused at once
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


def _parse_marker(src: str, path: str, t: dict[str, Any]) -> Marker:
    keys = ["id", "x", "y", "z", "yaw", "size", "dictionary"]
    _check_keys(src, path, t, keys, ["id", "x", "y", "yaw"])
    dictionary = _str(src, f"{path}.dictionary", t.get("dictionary", "DICT_4X4_50"))
    if dictionary not in DICTIONARIES:
        close = close_matches(dictionary, list(DICTIONARIES))
        hint = f" (did you mean '{close[0]}'?)" if close else ""
        raise field_error(
            src, f"{path}.dictionary", f"unknown ArUco dictionary {dictionary!r}{hint}"
        )
    mid = _int(src, f"{path}.id", t["id"])
    if mid >= DICTIONARIES[dictionary]:
        raise field_error(
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
        raise field_error(src, path, f"must be [x, y], got {value!r}")
    return (_num(src, f"{path}[0]", value[0]), _num(src, f"{path}[1]", value[1]))


def _parse_task(src: str, table: Any, prefix: str = "task") -> tuple[tuple[str, float | str], ...]:
    """The ``[task]`` table flattened to sorted ``dotted.key -> number | string`` pairs."""
    if not isinstance(table, dict):
        raise field_error(src, prefix, "must be a table")
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


# --- writing ----------------------------------------------------------------------------------


def to_toml(scn: Scenario) -> str:
    """The scenario as TOML text; ``from_toml(to_toml(s)) == s`` exactly (floats by repr)."""
    data = _head_tables(scn)
    data["walls"] = [_wall_table(w) for w in scn.walls]
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
    return _dump(data)


def _head_tables(scn: Scenario) -> dict[str, Any]:
    """Everything before the ``[[walls]]``, in the file's order (the order is the log's bytes:
    a recording attaches this text)."""
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
        "pixel_fields_width": cam.pixel_fields_width,
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
    return data


def _wall_table(w: Box) -> dict[str, Any]:
    """A wall, its thickness and height only where they differ from the standard wall's."""
    table: dict[str, Any] = {
        "name": w.name,
        "x": w.x,
        "y": w.y,
        "yaw": w.yaw,
        "length": w.size_x,
    }
    if w.size_y != WALL_THICKNESS:
        table["thickness"] = w.size_y
    if w.size_z != WALL_HEIGHT or w.z != w.size_z / 2:
        table["height"] = w.size_z
    return table


def _dump(data: dict[str, Any]) -> str:
    """The tables as TOML, ``[x, y]`` pairs on one line, with the header and unit comments."""
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
    ("camera", "pixel_fields_width"): "px, detections' pixel fields as this wide (0: own)",
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
