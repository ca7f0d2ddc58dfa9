"""core/settings: one codec between settings, TOML, --set and the log, with units and ranges."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from usar_replay.core import settings as s
from usar_replay.core.errors import UsageError


def test_a_run_round_trips_through_toml() -> None:
    run = s.RunSettings(
        record=s.RecordSettings(control_hz=10, max_sim_time_s=90.0),
        mission=s.MissionSettings(settle_frames=3),
        detector=s.DetectorParams(dictionary="DICT_5X5_100"),
    )
    text = s.to_toml(run)
    assert "[record]" in text and "control_hz = 10" in text
    assert s.from_toml(s.RunSettings, text) == run
    assert "max_sim_time_s" not in s.to_toml(s.RunSettings())  # unset is left out
    assert s.from_toml(s.RunSettings, "") == s.RunSettings()


@pytest.mark.parametrize(
    ("text", "why"),
    [
        ("[mission]\nsettle_frames = -3\n", "mission.settle_frames: -3 is out of range [1, 1000]"),
        ("[mission]\nspin_speed = 0\n", "mission.spin_speed: 0.0 is out of range (0, 1.82] rad/s"),
        ("[mission]\nsettle_frames = 2.5\n", "settle_frames: expected a whole number, got 2.5"),
        ("[mission]\nspin_speed = nan\n", "spin_speed: expected a finite number, got nan"),
        ("[mission]\nspin_speed = true\n", "spin_speed: expected a number, got True"),
        ("[mission]\nspin = 1\n", "mission.spin: unknown setting (known: mission.spin_speed,"),
        ("mission = 3\n", "mission: expected a table [mission]"),
        ("[detector]\ndictionary = 'DICT_9X9'\n", "'DICT_9X9' is not one of DICT_4X4_50,"),
        ("[detector]\ndictionary = 4\n", "detector.dictionary: expected a string, got 4"),
        ("[mission\n", "invalid TOML"),
    ],
)
def test_a_bad_value_is_one_error_naming_the_source_and_the_key(text: str, why: str) -> None:
    with pytest.raises(UsageError) as caught:
        s.from_toml(s.RunSettings, text, "run.toml")
    assert str(caught.value).startswith("run.toml: ")
    assert why in str(caught.value)


def test_settings_built_in_python_are_checked_too() -> None:
    with pytest.raises(UsageError, match=r"record\.control_hz: 0 is out of range \[1, 1000\] Hz"):
        s.RecordSettings(control_hz=0)
    with pytest.raises(UsageError, match=r"thresholds\.home_m: expected a finite number, got inf"):
        s.Thresholds(home_m=math.inf)


def test_a_table_of_a_shared_file(tmp_path: Path) -> None:
    path = tmp_path / "grader.toml"
    path.write_text("[thresholds]\nhome_m = 0.3\n[other]\nx = 1\n", encoding="utf-8")
    got = s.load(s.Thresholds, path, table="thresholds")
    assert got.home_m == 0.3 and got.time_limit_s is None
    with pytest.raises(UsageError, match=r"grader.toml: expected a \[record\] table"):
        s.load(s.RecordSettings, path, table="record")
    with pytest.raises(UsageError, match=r"nope.toml: no such settings file"):
        s.load(s.Thresholds, tmp_path / "nope.toml")
    (tmp_path / "bin.toml").write_bytes(b"\xff\xfe")
    with pytest.raises(UsageError, match="cannot read the settings file: UnicodeDecodeError"):
        s.load(s.Thresholds, tmp_path / "bin.toml")


def test_overrides_parse_by_the_fields_type() -> None:
    run = s.apply_overrides(
        s.RunSettings(),
        {"spin_speed": "0.2", "record.renderer": "tiny", "record.max_sim_time_s": "30"},
        default_group="mission",
    )
    assert run.mission.spin_speed == 0.2 and run.record.renderer == "tiny"
    assert run.record.max_sim_time_s == 30.0
    assert s.apply_overrides(s.RunSettings(), {}) == s.RunSettings()


@pytest.mark.parametrize(
    ("key", "raw", "why"),
    [
        ("mission", "1", "--set mission: a group of settings; set one of its fields"),
        ("mission.spin_speed.x", "1", "--set mission.spin_speed.x: mission.spin_speed is not a"),
        ("mission.nope", "1", "--set mission.nope: unknown setting (known: mission.spin_speed"),
        ("mission.settle_frames", "many", "expected a whole number, got 'many'"),
        ("mission.settle_frames", "0", "--set mission.settle_frames: 0 is out of range"),
    ],
)
def test_a_bad_override_says_what_is_wrong(key: str, raw: str, why: str) -> None:
    with pytest.raises(UsageError) as caught:
        s.apply_overrides(s.RunSettings(), {key: raw})
    assert why in str(caught.value)


def test_describe_gives_names_with_units() -> None:
    rows = dict(s.describe(s.RunSettings()))
    assert rows["mission.spin_speed"] == "0.1 rad/s"
    assert rows["record.max_sim_time_s"] == "unset"
    assert rows["detector.dictionary"] == "DICT_4X4_50"
    assert rows["record.control_hz"] == "20 Hz"
