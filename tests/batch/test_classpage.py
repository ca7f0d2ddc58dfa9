"""The class on one page (issue 42): a row per team and world, points per section-9 question, the
start used and where it was read, the verdict with its reason, links to the runs' pages; and the
page as a person sees it, rendered by headless Chromium.
"""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from usar_replay.batch.classpage import class_page, question_of
from usar_replay.batch.classreport import (
    ClassGrades,
    class_json,
    collect,
    from_folder,
    gradescope_results,
    to_csv,
    to_table,
)
from usar_replay.batch.plan import GRADE_FORMAT, Plan, Submission, World

CHECKS = [
    ("explorer.target_1", 4.0, 4.0),
    ("marker_0.detected", 4.0, 4.0),
    ("marker_0.broadcast", 0.0, 8.0),
    ("marker_frame.only_on_detection", 4.0, 4.0),
    ("follower.marker_0", 6.0, 6.0),
    ("follower.home", 4.0, 4.0),
    ("time_limit", 4.0, 4.0),
]


def _class(tmp_path: Path) -> Plan:
    subs = [
        Submission(
            "alpha",
            tmp_path,
            "ros1:x",
            "",
            start="roslaunch final_project multiple_robots.launch; rosrun final_project n",
            start_source="doc/instructions.txt lines 3, 4",
        ),
        Submission(
            "beta",
            tmp_path,
            "",
            "",
            "package p: no roslaunch/rosrun line of it ... (a_node, b_node)",
        ),
    ]
    plan = Plan(tmp_path, subs, [World("room", "", "room")])
    (tmp_path / "alpha").mkdir()
    checks = [
        {"id": i, "description": i, "passed": p == m, "points": p, "max_points": m, "measured": ""}
        for i, p, m in CHECKS
    ]
    grade = {
        "format": GRADE_FORMAT,
        "outcome": "done",
        "points": 26.0,
        "max_points": 34.0,
        "checks": checks,
        "start": "roslaunch final_project multiple_robots.launch; rosrun final_project n",
        "start_source": "doc/instructions.txt lines 3, 4",
    }
    (tmp_path / "alpha" / "room.grade.json").write_text(json.dumps(grade))
    return plan


def _grades(tmp_path: Path) -> ClassGrades:
    return collect(_class(tmp_path), {"room": 34.0})


def test_questions_follow_the_handouts_section_9() -> None:
    assert [question_of(i) for i, _, _ in CHECKS] == [
        "targets",
        "detected",
        "broadcast",
        "broadcast",
        "follower",
        "follower",
        "time",
    ]
    assert question_of("explorer.cmd_vel_one_publisher") == "other"


def test_the_start_and_the_problem_are_in_every_summary(tmp_path: Path) -> None:
    grades = _grades(tmp_path)
    table = to_table(grades)
    assert "beta: no_mission: package p: no roslaunch/rosrun line" in table
    assert "alpha: roslaunch final_project multiple_robots.launch; rosrun final_project n" in table
    assert "(doc/instructions.txt lines 3, 4)" in table
    assert all(len(line) <= 100 for line in table.splitlines())
    rows = to_csv(grades).splitlines()
    assert rows[0].endswith("problems,start,start_from")
    assert rows[1].endswith(
        "roslaunch final_project multiple_robots.launch; rosrun final_project n,"
        "\"doc/instructions.txt lines 3, 4\""
    )
    assert "(a_node, b_node)" in rows[2]
    gs = gradescope_results(grades, "alpha", {}, execution_time_s=1.0)
    assert "Started with: roslaunch final_project" in gs["output"]
    assert "doc/instructions.txt lines 3, 4" in gs["tests"][0]["output"]
    beta = gradescope_results(grades, "beta", {}, execution_time_s=0.0)
    assert beta["score"] == 0 and "(a_node, b_node)" in beta["output"]


def test_the_page_has_a_row_per_team_with_points_per_question(tmp_path: Path) -> None:
    grades = _grades(tmp_path)
    page = class_page(grades, lambda team, world: f"{team}-{world}.html")
    assert "<th>properly broadcast</th>" in page
    assert "4/12" in page  # broadcast: 0 of 8 and 4 of 4
    assert "10/10" in page  # follower visits and home
    assert "<a href='alpha-room.html'>room</a>" in page
    assert "doc/instructions.txt lines 3, 4" in page
    assert "no_mission" in page and "(a_node, b_node)" in page


def test_a_batch_folder_gives_the_same_class_back(tmp_path: Path) -> None:
    grades = _grades(tmp_path)
    (tmp_path / "class.json").write_text(class_json(grades))
    again = from_folder(tmp_path)
    assert again is not None
    assert (again.teams, again.worlds, again.problems, again.starts) == (
        grades.teams,
        grades.worlds,
        grades.problems,
        grades.starts,
    )
    assert again.cells[("beta", "room")].outcome == "no_mission"
    assert from_folder(tmp_path / "alpha") is None


def test_the_page_in_a_real_browser(tmp_path: Path) -> None:
    chromium = shutil.which("chromium")
    if chromium is None:
        pytest.fail("Debian's chromium is not installed: the README's apt-get line installs it")
    page = tmp_path / "class.html"
    page.write_text(class_page(_grades(tmp_path), lambda t, w: None), encoding="utf-8")
    shot = tmp_path / "shot.png"
    subprocess.run(
        [
            chromium,
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--window-size=1200,500",
            f"--screenshot={shot}",
            page.as_uri(),
        ],
        capture_output=True,
        timeout=120,
        check=True,
    )
    image = np.asarray(Image.open(shot).convert("RGB")).astype(int)
    assert image.shape[:2] == (500, 1200)
    dark = (image.sum(axis=2) < 200).mean()  # text drawn
    red = ((image[..., 0] > 150) & (image[..., 1] < 60) & (image[..., 2] < 60)).mean()
    green = ((image[..., 1] > 100) & (image[..., 0] < 40) & (image[..., 2] < 40)).mean()
    assert dark > 0.005, "the page rendered no text"
    assert red > 0 and green > 0, "the verdicts are not coloured"
