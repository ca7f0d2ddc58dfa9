"""world/scenario_toml: a world to TOML and back, and a bad file named by its field."""

from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from usar_replay.core.errors import InvalidScenario, UsageError
from usar_replay.world import scenario as scn
from usar_replay.world import scenario_toml


def test_toml_round_trip_course(tmp_path: Path) -> None:
    c = scn.course_world()
    assert scenario_toml.from_toml(scenario_toml.to_toml(c)) == c
    path = tmp_path / "course.toml"
    scenario_toml.save(c, path)
    assert scenario_toml.load(path) == c
    assert "[aruco_lookup_locations]" in path.read_text()


def test_the_pixel_fields_width_travels_and_an_older_file_means_the_images_own() -> None:
    """The course world writes ``pixel_fields_width = 1920``; a file from before the field (a
    log recorded then) reads as 0, the images' own pixels, which is what its detector reported,
    so its detections replay unchanged."""
    text = scenario_toml.to_toml(scn.course_world())
    assert "pixel_fields_width = 1920" in text
    old = scenario_toml.from_toml(re.sub(r"(?m)^pixel_fields_width = 1920.*\n", "", text))
    assert old.camera.pixel_fields_width == 0 and old.camera.pixel_scale() == 1.0
    bad = text.replace("pixel_fields_width = 1920", "pixel_fields_width = -1")
    with pytest.raises(InvalidScenario, match=r"camera\.pixel_fields_width"):
        scenario_toml.from_toml(bad)


finite = st.floats(min_value=-3.0, max_value=3.0, allow_nan=False)


@settings(max_examples=30, deadline=None)
@given(
    marker_xy=st.tuples(finite, finite),
    yaw=st.floats(min_value=-math.pi, max_value=math.pi),
    size=st.floats(min_value=0.01, max_value=1.0),
    targets=st.lists(st.tuples(finite, finite), min_size=1, max_size=6),
    seed=st.one_of(st.none(), st.integers(0, 2**31)),
)
def test_toml_round_trip_random(
    marker_xy: tuple[float, float],
    yaw: float,
    size: float,
    targets: list[tuple[float, float]],
    seed: int | None,
) -> None:
    c = dataclasses.replace(
        scn.course_world(),
        markers=(scn.Marker(id=7, x=marker_xy[0], y=marker_xy[1], yaw=yaw, size=size),),
        targets=tuple(targets),
        seed=seed,
    )
    assert scenario_toml.from_toml(scenario_toml.to_toml(c)) == c


def _broken(edit: str, new: str) -> str:
    text = scenario_toml.to_toml(scn.course_world())
    assert edit in text
    return text.replace(edit, new, 1)


@pytest.mark.parametrize(
    ("edit", "new", "expected"),
    [
        ("size = 0.15", "size = -0.1", "markers[0].size: must be a positive number, got -0.1"),
        (
            "length = 8.0 }",
            "lenght = 8.0 }",
            "walls[0].lenght: unknown field (did you mean 'length'?)",
        ),
        ("target_3 = ", "target_9 = ", "missing target_3"),
        ("x = -5.033", 'x = "far"', "walls[0].x: must be a number"),
        ("x = -5.033", "x = nan", "walls[0].x: must be finite"),
        ("id = 1\n", "id = 0\n", "markers[1].id: duplicate marker id 0"),
        ("id = 1\n", "id = 50\n", "markers[1].id: 50 is outside DICT_4X4_50"),
        ('"DICT_4X4_50"', '"DICT_4X4_5O"', "unknown ArUco dictionary"),
        ("width = 640", "width = 0", "camera.width: must be >= 16"),
        ('encoding = "jpeg"', 'encoding = "gif"', "camera.encoding"),
        ("time_limit_s = 600.0", "time_limit_s = -1.0", "time_limit_s: must be a positive"),
        (
            "target_1 = [",
            "target_1 = [40.0, 0.0, ",
            "aruco_lookup_locations.target_1: must be [x, y]",
        ),
        ("target_1 = [-1.752882", "target_1 = [40.0", "target_1: (40.0, 3.246192) is outside"),
        ('name = "course"', 'name = "course', "invalid TOML"),
    ],
)
def test_invalid_files_name_the_field(edit: str, new: str, expected: str) -> None:
    with pytest.raises(InvalidScenario) as info:
        scenario_toml.from_toml(_broken(edit, new), source="s.toml")
    text = str(info.value)
    assert text.startswith("s.toml: ") and expected in text
    assert "\n" not in text


def test_missing_file_is_an_invalid_scenario(tmp_path: Path) -> None:
    with pytest.raises(InvalidScenario, match="no such scenario file"):
        scenario_toml.load(tmp_path / "nope.toml")


def test_save_refuses_to_replace_a_file_without_overwrite(tmp_path: Path) -> None:
    path = tmp_path / "w.toml"
    path.write_text("mine", encoding="utf-8")
    with pytest.raises(UsageError, match="exists; pass --overwrite"):
        scenario_toml.save(scn.course_world(), path)
    assert path.read_text(encoding="utf-8") == "mine"
    scenario_toml.save(scn.course_world(), path, overwrite=True)
    assert scenario_toml.load(path) == scn.course_world()


def test_an_oversized_or_unreadable_file_is_refused_unread(tmp_path: Path) -> None:
    big = tmp_path / "big.toml"
    with open(big, "wb") as f:
        f.truncate(scenario_toml.MAX_FILE_BYTES + 1)
    with pytest.raises(InvalidScenario, match=r"big.toml: the file is \d+ bytes; a scenario is"):
        scenario_toml.load(big)
    (tmp_path / "bin.toml").write_bytes(b"\xff\xfe")
    with pytest.raises(InvalidScenario, match="cannot read the scenario"):
        scenario_toml.load(tmp_path / "bin.toml")
