"""``usar replay`` of a ROS 1 log re-runs the recorded package (docs/ros1.md): bit for bit when
unchanged (exit 0); a changed package, or one that reads the wall clock, is named at its first
differing message (exit 1), with the rubric delta under ``--grade``."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from clitools import usar
from example_worlds import quick_room

from usar_replay.core.settings import RunSettings
from usar_replay.log.run import open_run

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "ros1" / "usar_course"


@pytest.fixture(scope="module")
def wall_clock_package(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The example, whose last log line prints the wall clock: not repeatable."""
    pkg = tmp_path_factory.mktemp("wall") / "usar_course"
    shutil.copytree(EXAMPLE, pkg)
    main = pkg / "src" / "main.cpp"
    text = main.read_text(encoding="utf-8")
    line = 'ROS_INFO("mission complete");'
    assert line in text
    wall = 'ROS_INFO("mission complete at wall %.6f", ros::WallTime::now().toSec());'
    main.write_text(text.replace(line, wall), encoding="utf-8")
    return pkg


def _record(path: Path, package: Path) -> Path:
    from usar_replay.ros1.record import record_ros1

    result = record_ros1(quick_room(), path, package, RunSettings())
    assert result.outcome == "done", result
    return path


@pytest.fixture(scope="module")
def example_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return _record(tmp_path_factory.mktemp("replay") / "example.mcap", EXAMPLE)


def test_an_unchanged_package_replays_bit_for_bit(example_log: Path) -> None:
    # the graph reacted while the simulator stepped on (record.actuation_latency_ticks unset:
    # 1 for a ROS 1 package), and the log says so
    assert open_run(example_log).settings.record.actuation_latency_ticks == 1
    done = usar("replay", "--grade", str(example_log))
    assert done.returncode == 0, done.stdout + done.stderr
    assert "bit for bit" in done.stdout
    assert "DIFFERENT" not in done.stdout
    assert "Total: 60 / 60 points: PASS" in done.stdout  # graded again from the replay
    # the folder the log names is built only after saying so, its sha256 checked (issue 33)
    assert f"replaying the recorded package {EXAMPLE}: its sha256" in done.stderr


def test_a_changed_package_shows_the_first_difference_and_the_rubric_delta(
    example_log: Path, wall_clock_package: Path
) -> None:
    done = usar("replay", str(example_log), "--ros1", str(wall_clock_package), "--grade")
    assert done.returncode == 1, done.stdout + done.stderr
    assert "First divergence: /rosout" in done.stdout
    assert "Rubric:" in done.stdout and "total 60 -> 60 of 60" in done.stdout


def test_a_package_reading_the_wall_clock_names_where_it_diverged(
    tmp_path: Path, wall_clock_package: Path
) -> None:
    log = _record(tmp_path / "wall.mcap", wall_clock_package)
    done = usar("replay", str(log))
    assert done.returncode == 1, done.stdout + done.stderr
    first = [line for line in done.stdout.splitlines() if line.startswith("First divergence")]
    assert first and first[0].startswith("First divergence: /rosout message #8 at sim time")
    # everything before the wall-clock line replays identically
    assert "/explorer/cmd_vel      recorded" in done.stdout
    assert all("identical" in line for line in done.stdout.splitlines() if "/cmd_vel" in line)
