"""cli/options: what record, replay, scenario, grade and batch read from their arguments."""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import pytest

from usar_replay.cli import options
from usar_replay.core.errors import UsageError
from usar_replay.core.settings import RunSettings
from usar_replay.world.scenario import course_world
from usar_replay.world.scenario_toml import save
from usar_replay.world.world_key import ENV_VAR

KEY = "0123456789abcdef0123456789abcdef"


def _world_args(*argv: str) -> argparse.Namespace:
    p = argparse.ArgumentParser()
    options.add_world_options(p)
    return p.parse_args(argv)


def test_parse_camera() -> None:
    assert options.parse_camera("640x480@10") == (640, 480, 10.0)
    assert options.parse_camera(" 320x240 ") == (320, 240, 10.0)
    assert options.parse_camera("320x240@2.5") == (320, 240, 2.5)
    with pytest.raises(UsageError, match="expected WIDTHxHEIGHT"):
        options.parse_camera("640 by 480")
    with pytest.raises(UsageError, match=r"size 16\.\.4096 pixels and rate 0\.\.60 Hz"):
        options.parse_camera("8x8@10")
    with pytest.raises(UsageError, match="rate"):
        options.parse_camera("640x480@61")


def test_overrides() -> None:
    assert options.overrides(None) == {}
    assert options.overrides([" a.b = 1 ", "c=x=y"]) == {"a.b": "1", "c": "x=y"}
    for bad in ("novalue", "=3"):
        with pytest.raises(UsageError, match="expected NAME=VALUE"):
            options.overrides([bad])


def test_the_world_the_options_name(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv(ENV_VAR, raising=False)
    course = course_world()
    assert options.load_scenario(_world_args()) == course
    got = options.load_scenario(_world_args("--camera", "320x240@5", "--encoding", "jpeg"))
    assert (got.camera.width, got.camera.height, got.camera.rate_hz) == (320, 240, 5.0)
    assert got.camera.encoding == "jpeg" and got.markers == course.markers
    seeded = options.load_scenario(_world_args("--seed", "3"))
    assert seeded != course and seeded == options.load_scenario(_world_args("--seed", "3"))
    path = tmp_path / "w.toml"
    save(course, path)
    assert options.load_scenario(_world_args("--scenario", str(path))) == course
    with pytest.raises(UsageError, match="is a 'usar' world, not 'ros2-final'"):
        options.load_scenario(_world_args("--scenario", str(path), "--assignment", "ros2-final"))
    with pytest.raises(UsageError, match=r"--assignment nope: no such assignment \(known: "):
        options.load_scenario(_world_args("--assignment", "nope"))


def test_the_world_key_is_taken_out_of_the_environment(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv(ENV_VAR, KEY)
    from_env = options.world_key(_world_args())
    assert from_env is not None and ENV_VAR not in os.environ
    assert options.world_key(_world_args()) is None  # gone for whatever starts later
    path = tmp_path / "k"
    path.write_text(KEY[::-1], encoding="utf-8")
    from_file = options.world_key(_world_args("--world-key", str(path)))
    assert from_file is not None and from_file.digest != from_env.digest
    keyed = options.load_scenario(_world_args("--seed", "3", "--world-key", str(path)))
    assert keyed != options.load_scenario(_world_args("--seed", "3"))


def test_run_settings_file_then_set(tmp_path: Path) -> None:
    path = tmp_path / "s.toml"
    path.write_text("[mission]\nsettle_frames = 7\n", encoding="utf-8")
    args = argparse.Namespace(settings=str(path), set=["spin_speed=0.2", "record.control_hz=10"])
    got = options.run_settings(args, RunSettings())
    assert got.mission.settle_frames == 7 and got.mission.spin_speed == 0.2
    assert got.record.control_hz == 10
    assert got.detector == RunSettings().detector  # a table the file lacks is the base's
    with pytest.raises(UsageError, match="unknown setting"):
        options.run_settings(argparse.Namespace(settings=None, set=["nope=1"]), RunSettings())


def test_the_settings_given_explicitly(tmp_path: Path) -> None:
    """What a ROS 1 run lets win over the package's own files (move_base's tolerances)."""
    path = tmp_path / "s.toml"
    path.write_text("[mission]\nyaw_tolerance = 0.3\n", encoding="utf-8")
    args = argparse.Namespace(settings=str(path), set=["xy_tolerance=0.2", "record.control_hz=10"])
    assert options.given_settings(args) == (
        "mission.xy_tolerance",
        "mission.yaw_tolerance",
        "record.control_hz",
    )
    assert options.given_settings(argparse.Namespace(settings=None, set=None)) == ()


def _limit_args(**kw: object) -> argparse.Namespace:
    base: dict[str, object] = {
        "tick_timeout": 5.0,
        "mission_memory": 0,
        "max_log_mib": 10,
        "run_memory": 3072,
        "processes": 256,
        "run_folder": 512,
        "max_holds": 20,
        "max_capped": 600,
        "wall_limit": 3600.0,
    }
    return argparse.Namespace(**{**base, **kw})


def test_limits_and_the_files_hidden_from_the_mission() -> None:
    args = _limit_args(scenario="w.toml", out="r.mcap", json=None)
    got = options.limits(args)
    assert (got.tick_timeout_s, got.memory_mb, got.max_log_mib) == (5.0, 0, 10)
    assert got.hidden == ("w.toml", "r.mcap")
    assert (got.run_memory_mb, got.processes, got.run_folder_mb) == (3072, 256, 512)
    assert (got.max_holds, got.max_capped, got.wall_s) == (20, 600, 3600.0)
    for kw, why in [
        ({"tick_timeout": 0.0}, "--tick-timeout 0.0: expected a positive"),
        ({"tick_timeout": float("nan")}, "--tick-timeout nan"),
        ({"mission_memory": -1}, "--mission-memory -1"),
        ({"max_log_mib": -1}, "--max-log-mib -1"),
        ({"run_memory": -1}, r"--run-memory -1: expected MiB >= 0 \(0: none\)"),
        ({"run_folder": -1}, r"--run-folder -1: expected MiB >= 0 \(0: no limit\)"),
        ({"processes": 0}, "--processes 0"),
        ({"max_holds": -1}, r"--max-holds -1: expected 0 \(no budget\) or more"),
        ({"max_capped": 1.5}, "--max-capped 1.5: expected a whole number"),
        ({"hold_wall": float("inf")}, "--hold-wall inf: expected seconds >= 0"),
        ({"wall_limit": -1.0}, "--wall-limit -1"),
    ]:
        with pytest.raises(UsageError, match=why):
            options.limits(_limit_args(**kw))


def test_check_outputs_refuses_one_path_for_two_options(tmp_path: Path) -> None:
    out = str(tmp_path / "g.json")
    args = argparse.Namespace(json=out, junit=out, csv=None, overwrite=False)
    with pytest.raises(UsageError, match=r"--junit .*g.json: also given to --json"):
        options.check_outputs(args, [])
    log = str(tmp_path / "r.mcap")
    args = argparse.Namespace(json=None, junit=None, csv=log, overwrite=True, file=None)
    with pytest.raises(UsageError, match="is an input"):
        options.check_outputs(args, [log])
    options.check_outputs(argparse.Namespace(json=out, junit=None, csv=None, overwrite=False), [])


def test_find_recordings(tmp_path: Path) -> None:
    for name in ("b/2.mcap", "a.mcap", ".hidden/x.mcap", "c.mcap.part", "notes.txt"):
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_bytes(b"")
    assert options.find_recordings([str(tmp_path), "given.mcap"]) == [
        str(tmp_path / "a.mcap"),
        str(tmp_path / "b" / "2.mcap"),
        "given.mcap",
    ]
    (tmp_path / "empty").mkdir()
    with pytest.raises(UsageError, match=r"no \.mcap files in this folder"):
        options.find_recordings([str(tmp_path / "empty")])
