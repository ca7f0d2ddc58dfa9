"""Malformed and impossible scenarios: refused on load with the field named, or failed by --check.

Each case is one a hostile user tried (issue 13): numbers that allocate terabytes, hang or crash
the recorder, names that escape ``recordings/``, worlds that parse but cannot be completed.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from clitools import one_error_line, usar

from usar_replay.world import scenario as scn
from usar_replay.world import scenario_toml

COURSE = scenario_toml.to_toml(scn.course_world())


def _edit(old: str, new: str) -> str:
    assert old in COURSE, old
    return COURSE.replace(old, new, 1)


@pytest.mark.parametrize(
    ("old", "new", "expected"),
    [
        ("length = 8.0 }", "length = 1e12 }", "walls[0].length: must be between 0.01 and 50 m"),
        ("x = -5.033", "x = -1e300", "walls[0].x: must be between -100 and 100 m"),
        ("width = 640", "width = 100000", "camera.width: must be between 16 and 4096 px"),
        ("rate_hz = 10.0", "rate_hz = 1e9", "camera.rate_hz: must be between 0.5 and 60 Hz"),
        ("rate_hz = 10.0", "rate_hz = 1e-9", "camera.rate_hz"),
        ("hfov = 1.3439", "hfov = 0.001", "camera.hfov"),
        ("z = 0.2", "z = 100.0", "markers[0].z: must be between 0.05 and 2 m"),
        ("size = 0.15", "size = 1e-9", "markers[0].size: must be between 0.01 and 1 m"),
        ("yaw = -1.5707\n", "yaw = 1e9\n", "markers[0].yaw: must be between"),
        ("time_limit_s = 600.0", "time_limit_s = 1e9", "time_limit_s: must be between 1 and 3600"),
        ('name = "course"', 'name = "../escaped"', "name: '../escaped' is not a plain file name"),
        ('name = "course"', 'name = "/tmp/abs"', "is not a plain file name"),
        ('name = "course"', 'name = "a/b"', "is not a plain file name"),
        ('name = "course"', 'name = ".hidden"', "is not a plain file name"),
        ("radius = 0.2821", "radius = 1e6", "cylinders[0].radius: must be between"),
    ],
)
def test_out_of_range_numbers_are_refused_naming_the_field(
    old: str, new: str, expected: str
) -> None:
    with pytest.raises(scn.InvalidScenario) as info:
        scenario_toml.from_toml(_edit(old, new), source="s.toml")
    assert str(info.value).startswith("s.toml: ") and expected in str(info.value)
    assert "\n" not in str(info.value)


def test_too_many_objects_are_refused_before_parsing() -> None:
    boxes = "\n".join(
        f'[[boxes]]\nname = "b{i}"\nx = 0.0\ny = 0.0\nz = 0.5\nsize_x = 1.0\nsize_y = 1.0\n'
        "size_z = 1.0\nyaw = 0.0"
        for i in range(1001)
    )
    n = len(scn.course_world().boxes) + 1001
    with pytest.raises(scn.InvalidScenario, match=f"boxes: holds {n}; a scenario has 0 to 1000"):
        scenario_toml.from_toml(COURSE + "\n" + boxes)


def test_a_huge_file_is_refused_unread(tmp_path: Path) -> None:
    p = tmp_path / "big.toml"
    p.write_text(COURSE + "#" * (2 << 20))
    one_error_line(usar("scenario", "--scenario", str(p)), 2, "at most 1048576")


def test_every_range_is_documented() -> None:
    doc = (Path(__file__).resolve().parents[2] / "docs" / "scenario.md").read_text()
    for key, (lo, hi, _unit) in scn.RANGES.items():
        assert f"`{key}`" in doc, key
        assert f"{lo:g}" in doc and f"{hi:g}" in doc
    for key in scn.COUNTS:
        assert f"`{key}`" in doc, key


@pytest.mark.parametrize(
    ("old", "new", "expected"),
    [
        # marker 0 moved into the north wall (y 4.091) with its face still inside it
        ("x = -1.80731\ny = 4.0\n", "x = -1.80731\ny = 4.09\n", "marker 0: its face is inside"),
        # both robots at the same start
        (
            "[robots.follower]\nx = -4.0  # m\ny = 3.5",
            "[robots.follower]\nx = -4.0  # m\ny = 2.5",
            "the robots start 0.00 m apart",
        ),
        # a marker above the camera's view from its target
        ("x = -1.80731\ny = 4.0\nz = 0.2", "x = -1.80731\ny = 4.0\nz = 1.9", "vertical view"),
        # a marker too small to read
        ("size = 0.15\n", "size = 0.01\n", "px wide in the image"),
        # a camera too slow to see a marker while spinning
        ("rate_hz = 10.0", "rate_hz = 0.5", "frames at 0.5 Hz"),
        # a target too far from its marker
        ("target_4 = [7.710214, -1.716889]", "target_4 = [5.0, -1.7]", "beyond 2.5 m"),
    ],
)
def test_check_fails_a_world_that_cannot_be_completed(
    tmp_path: Path, old: str, new: str, expected: str
) -> None:
    p = tmp_path / "w.toml"
    p.write_text(_edit(old, new))
    out = usar("scenario", "--scenario", str(p), "--check")
    assert out.returncode == 1, out.stderr
    assert out.stderr == ""  # a verdict, not an error
    assert "CANNOT be completed" in out.stdout and expected in out.stdout
    assert max(len(line) for line in out.stdout.splitlines()) <= 100


def test_check_passes_the_course_world() -> None:
    out = usar("scenario", "--check")
    assert out.returncode == 0 and out.stderr == ""
    assert out.stdout.startswith("scenario course: can be completed")


def test_scenario_toml_has_units_and_loads_back() -> None:
    assert "# s, the mission's time limit" in COURSE and "px (16..4096)" in COURSE
    assert scenario_toml.from_toml(COURSE) == scn.course_world()
    assert max(len(line) for line in COURSE.splitlines()) <= 100
