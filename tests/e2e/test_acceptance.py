"""The course world end to end (slow: about 7 minutes of recording on 2 cores).

Run with ``python -m pytest -m slow``. This is the issue's acceptance on the real course world:
all four markers found and broadcast within 5 cm of the truth, the follower visits them in ID
order, both robots return home within the 10-minute limit, the rubric gives 60/60, and the
replay from the log reproduces every mission output bit for bit.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from usar_replay.grading.grade import grade_file
from usar_replay.pipeline.record import record
from usar_replay.pipeline.replay import replay
from usar_replay.world.scenario import course_world

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def course_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("course") / "course.mcap"
    result = record(course_world(), path)
    assert result.mission_done
    assert sorted(result.markers_found) == [0, 1, 2, 3]
    assert max(result.marker_errors_m.values()) < 0.05
    assert result.sim_duration_s <= 600.0
    return path


def test_course_world_grades_full_marks(course_log: Path) -> None:
    report = grade_file(course_log)
    failed = [c.id for c in report.checks if not c.passed]
    assert failed == [] and report.points == report.max_points == 60


def test_course_world_replays_bit_for_bit(course_log: Path) -> None:
    report = replay(course_log)
    assert report.identical, "\n".join(report.lines())
    assert report.topics["/fiducial_transforms"].identical > 4000
