"""The `usar` command as a user runs it: help, not-yet-built commands, `usar info`, exit codes."""

from __future__ import annotations

from pathlib import Path

import pytest
from clitools import usar

from usar_replay.cli.main import main
from usar_replay.core import msgs
from usar_replay.log import bag

T0 = 1_000_000_000


def _log(path: Path, *, interrupted: bool = False) -> None:
    w = bag.BagWriter(path)
    w.add_metadata(bag.RUN_METADATA, {"camera": "640x480@10"})
    for i in range(30):
        t = T0 + i * 100_000_000
        w.write("/explorer/cmd_vel", msgs.Twist(angular=msgs.Vector3(z=0.1)), t)
        w.write("/rosout", msgs.Log(stamp=msgs.Time.from_ns(t), level=20, msg=f"tick {i}"), t)
    w.close("interrupted" if interrupted else "complete")


def test_help_lists_every_command() -> None:
    out = usar("--help")
    assert out.returncode == 0
    for name in ("record", "replay", "grade", "view", "info"):
        assert name in out.stdout


def test_info_reports_topics_counts_duration(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "run.mcap"
    _log(path)
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "/explorer/cmd_vel" in out and "geometry_msgs/msg/Twist" in out
    assert "/rosout" in out and "rcl_interfaces/msg/Log" in out
    assert "Duration:      2.900 s" in out
    assert "File state:    complete" in out
    assert "camera = 640x480@10" in out


def test_info_on_an_interrupted_log_exits_3(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "run.mcap"
    _log(path, interrupted=True)
    assert main(["info", str(path)]) == 3
    assert "interrupted" in capsys.readouterr().out


def test_info_on_a_truncated_log_says_how_far(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    _log(path)
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(path.read_bytes()[:-300])
    out = usar("info", str(cut))
    assert out.returncode == 3
    assert "INCOMPLETE" in out.stdout and "messages up to sim time" in out.stdout
    assert "Traceback" not in out.stderr


@pytest.mark.parametrize(
    ("content", "code"), [(None, 2), (b"", 3), (b"PK\x03\x04 a zip, not a log", 3)]
)
def test_info_on_bad_files_is_one_line(tmp_path: Path, content: bytes | None, code: int) -> None:
    path = tmp_path / "bad.mcap"
    if content is not None:
        path.write_bytes(content)
    out = usar("info", str(path))
    assert out.returncode == code  # a missing file is a usage error (2), a bad one a bad log (3)
    assert out.stdout == ""
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("usar: error: ")
    assert str(path) in lines[0]


@pytest.mark.parametrize("command", ["replay", "grade"])
def test_missing_log_is_one_line_exit_2(command: str, tmp_path: Path) -> None:
    missing = tmp_path / "x.mcap"
    out = usar(command, str(missing))
    assert out.returncode == 2
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and "no such file" in lines[0] and str(missing) in lines[0]
    assert "Traceback" not in out.stderr


def test_scenario_writes_a_variant_that_loads_back(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from usar_replay.world.scenario import course_world
    from usar_replay.world.scenario_toml import load
    from usar_replay.world.variants import make_variant

    out = tmp_path / "demo3.toml"
    assert main(["scenario", "--seed", "3", "--out", str(out), "--check"]) == 0
    assert load(out) == make_variant(course_world(), 3)
    assert "can be completed" in capsys.readouterr().out
    # never replaced silently
    assert main(["scenario", "--out", str(out)]) == 2
    assert load(out).seed == 3


def test_scenario_check_fails_on_a_world_that_breaks_the_rules(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["scenario", "--out", str(tmp_path / "c.toml")]) == 0
    text = (tmp_path / "c.toml").read_text()
    # move target_1 behind the start-strip wall, out of sight of its marker
    bad = text.replace("target_1 = [-1.752882, 3.246192]", "target_1 = [-4.5, 0.6]")
    assert bad != text
    (tmp_path / "bad.toml").write_text(bad)
    capsys.readouterr()
    assert main(["scenario", "--scenario", str(tmp_path / "bad.toml"), "--check"]) == 1
    out = capsys.readouterr().out  # the verdict is plain output, not an error line
    assert "CANNOT be completed" in out and "FAIL  target_1" in out
