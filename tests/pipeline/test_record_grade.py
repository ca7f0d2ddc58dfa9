"""`usar record` grades while it records: the grade fed during the tick loop is the grade that a
separate ``usar grade`` of the finished file gives, line for line, for any way a run ends; and a
batch passes its thresholds as data and grades each log from the recorder's grade.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest
from conftest import one_room

from usar_replay.batch.run_one import max_points, rubric
from usar_replay.core.settings import RecordSettings, RunSettings, Thresholds
from usar_replay.grading.grade import grade_file
from usar_replay.grading.rubrics import rubric_for, rubric_of
from usar_replay.grading.verdict import GradeReport
from usar_replay.pipeline.record import RecordResult, record
from usar_replay.world.ros2_world import ros2_final_world
from usar_replay.world.scenario_toml import to_toml

CRASH_LATER = """
from usar_replay.api import Node, Twist


class Crash(Node):
    def __init__(self):
        super().__init__("crash")
        self.cmd = self.create_publisher(Twist, "/explorer/cmd_vel")
        self.n = 0
        self.create_timer(0.1, self.on_timer)

    def on_timer(self):
        self.n += 1
        self.cmd.publish(Twist())
        if self.n == 20:
            raise RuntimeError("deliberate bug after 2 s")


def main():
    Crash()
"""


def _same(live: GradeReport, filed: GradeReport) -> None:
    """Equal but for the wall time spent grading (JUnit's ``time``, never part of a verdict)."""
    assert dataclasses.replace(live, seconds=0.0) == dataclasses.replace(filed, seconds=0.0)


def test_the_recorders_grade_is_usar_grade_of_the_file(
    room_log: tuple[Path, RecordResult],
) -> None:
    path, result = room_log
    assert result.grade is not None
    live = result.grade.report(path)
    filed = grade_file(path)
    _same(live, filed)
    assert live.points == live.max_points  # the built-in mission: a graded run, not vacuous
    assert result.found == tuple(result.grade.found_markers())
    assert [f.marker_id for f in result.found] == [0]


def test_a_crashed_run_is_graded_the_same_live_and_from_the_file(tmp_path: Path) -> None:
    mission = tmp_path / "crash.py"
    mission.write_text(CRASH_LATER, encoding="utf-8")
    path = tmp_path / "crash.mcap"
    th = Thresholds(time_limit_s=30.0)
    result = record(one_room(), path, RunSettings(), mission=str(mission), thresholds=th)
    assert result.outcome == "crashed"
    assert result.grade is not None
    _same(result.grade.report(path), grade_file(path, th))


def test_a_run_that_never_ticked_is_graded_the_same_either_way(tmp_path: Path) -> None:
    """Issue 31: the world's facts at t0 are written before the mission starts, so a crash
    in ``main()`` leaves a gradable log whose every line fails with the reason."""
    mission = tmp_path / "at_start.py"
    mission.write_text("def main():\n    raise ValueError('at once')\n", encoding="utf-8")
    path = tmp_path / "start.mcap"
    result = record(one_room(), path, RunSettings(), mission=str(mission))
    assert result.outcome == "crashed"
    assert result.grade is not None
    live = result.grade.report(path)
    _same(live, grade_file(path))
    assert not any(c.passed for c in live.checks)
    assert all("ValueError: at once" in c.measured for c in live.checks)


def test_a_ros2_final_run_is_graded_the_same_live_and_from_the_file(tmp_path: Path) -> None:
    path = tmp_path / "ros2.mcap"
    settings = RunSettings(record=RecordSettings(max_sim_time_s=8.0))
    result = record(ros2_final_world(), path, settings)
    assert result.grade is not None
    live = result.grade.report(path)
    _same(live, grade_file(path))
    assert [c.id for c in live.checks] == [
        c.id for c in rubric_of("ros2-final").grader(ros2_final_world(), None).report("").checks
    ]


def test_batch_max_points_are_the_worlds_assignments() -> None:
    ros2 = ros2_final_world()
    full = rubric_for(ros2).grader(ros2, None).report("", log_complete=False)
    usar = rubric_of("usar").grader(one_room(), None).report("", log_complete=False)
    assert max_points(to_toml(ros2)) == round(full.max_points, 3)
    assert max_points(to_toml(one_room())) == round(usar.max_points, 3)
    assert full.max_points != usar.max_points or [c.id for c in full.checks] != [
        c.id for c in usar.checks
    ]


def test_a_ros2_final_world_in_a_batch_gets_its_own_rubric_when_the_mission_crashes(
    tmp_path: Path,
) -> None:
    """A mission that died before the first tick fails every line of the world's own rubric,
    not the US&R one, saying why (issue 31: its log is graded); thresholds travel as data."""
    from clitools import run_batch

    subs = tmp_path / "subs"
    subs.mkdir()
    (subs / "early.py").write_text("def main():\n    raise ValueError('at once')\n")
    world = tmp_path / "ros2.toml"
    world.write_text(to_toml(ros2_final_world()), encoding="utf-8")
    th = tmp_path / "th.toml"
    th.write_text("[thresholds]\ntime_limit_s = 99.0\n", encoding="utf-8")
    out = tmp_path / "out"
    code, text = run_batch(subs, world, out, "--quiet", "--thresholds", str(th))
    assert code == 0, text
    grade = json.loads(next((out / "early").glob("*.grade.json")).read_text())
    ros2 = ros2_final_world()
    expected = rubric_of("ros2-final").grader(ros2, None).report("")
    assert [c["id"] for c in grade["checks"]] == [c.id for c in expected.checks]
    assert grade["max_points"] == round(expected.max_points, 3)
    assert grade["points"] == 0.0
    assert not any(c["passed"] for c in grade["checks"])
    assert all("ValueError: at once" in c["measured"] for c in grade["checks"])


def test_batch_thresholds_are_data_not_a_file(
    room_log: tuple[Path, RecordResult], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The batch grades with its thresholds as given (TOML text), writing nothing to read back."""
    path, _ = room_log
    monkeypatch.chdir(tmp_path)  # a batch run's working directory is its scratch folder
    world = to_toml(one_room())
    relaxed = rubric(path, world, "")
    tight = rubric(path, world, "[thresholds]\ntime_limit_s = 0.5\n")
    assert relaxed["points"] == relaxed["max_points"]
    assert tight["points"] < relaxed["points"]
    assert list(tmp_path.iterdir()) == []
