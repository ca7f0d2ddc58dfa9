"""pipeline/replay_report: the replay's comparison as JSON, JUnit XML and CSV, parsed back."""

from __future__ import annotations

import csv
import io
import json
import xml.etree.ElementTree as ET

from usar_replay.grading.reports import SCHEMA_VERSION
from usar_replay.grading.verdict import Check, GradeReport
from usar_replay.pipeline.replay import Changes, Divergence, ReplayReport, TopicComparison
from usar_replay.pipeline.replay_report import (
    replay_dict,
    replay_to_csv,
    replay_to_json,
    replay_to_junit,
)

S = 1_000_000_000


def _report(*, diverged: bool, failure: str | None = None) -> ReplayReport:
    cmd = TopicComparison(
        "/explorer/cmd_vel", recorded=10, replayed=10, identical=9 if diverged else 10
    )
    tf = TopicComparison("/tf", recorded=3, replayed=3, identical=3)
    d = Divergence("/explorer/cmd_vel", 4, 5 * S, 5 * S, "linear.x", "0.2", "0.25")
    return ReplayReport(
        source="runs/team a.mcap",
        start_ns=S,
        topics={"/tf": tf, "/explorer/cmd_vel": cmd},
        divergence=d if diverged else None,
        digest="ab" * 32,
        inputs=120,
        changes=Changes(),
        regression=False,
        ticks=40,
        mission_failure=failure,
        mission_failure_detail="Traceback: boom" if failure else "",
    )


def test_the_comparison_as_plain_data() -> None:
    same = replay_dict(_report(diverged=False))
    assert same["identical"] is True and same["first_divergence"] is None
    assert [t["topic"] for t in same["topics"]] == ["/explorer/cmd_vel", "/tf"]  # type: ignore[index]
    diff = replay_dict(_report(diverged=True))
    assert diff["identical"] is False and diff["nondeterministic"] is True
    assert diff["first_divergence"] == {
        "topic": "/explorer/cmd_vel", "index": 4, "sim_time_s": 5.0,
        "field": "linear.x", "recorded": "0.2", "replayed": "0.25",
    }  # fmt: skip


def test_json_is_the_grade_document_plus_the_replay() -> None:
    grade = GradeReport(
        source="replayed.mcap",
        checks=(Check("a", "line a", True, 5, 5, "m", "t", None),),
        start_ns=S,
    )
    doc = json.loads(replay_to_json(_report(diverged=True), [grade]))
    assert doc["schema_version"] == SCHEMA_VERSION
    assert len(doc["recordings"]) == 1
    assert doc["replay"]["digest_sha256"] == "ab" * 32
    assert doc["replay"]["rubric_delta"] is None
    assert json.loads(replay_to_json(_report(diverged=False)))["recordings"] == []


def test_junit_has_a_case_per_topic_and_one_for_the_mission() -> None:
    root = ET.fromstring(replay_to_junit(_report(diverged=True, failure="crashed")))
    assert root.get("name") == "usar replay"
    suite = root.find("testsuite")
    assert suite is not None
    assert (suite.get("tests"), suite.get("failures")) == ("3", "2")
    cases = {c.get("name"): c for c in suite.iter("testcase")}
    assert list(cases) == ["mission.ran", "/explorer/cmd_vel", "/tf"]
    assert {c.get("classname") for c in cases.values()} == {"usar.replay.team_a"}
    mission = cases["mission.ran"].find("failure")
    assert mission is not None and mission.get("message") == "the mission crashed"
    assert mission.text == "Traceback: boom"
    cmd = cases["/explorer/cmd_vel"].find("failure")
    assert cmd is not None
    assert cmd.get("message") == (
        "recorded 10, replayed 10, identical 9; first divergence at 5.000 s: linear.x"
    )
    assert cases["/tf"].find("failure") is None
    assert root.get("failures") == "2"


def test_csv_is_one_row_per_topic() -> None:
    rows = list(csv.reader(io.StringIO(replay_to_csv(_report(diverged=True)))))
    assert rows[0] == ["schema_version", "source", "topic", "recorded", "replayed", "identical"]
    assert rows[1:] == [
        [str(SCHEMA_VERSION), "runs/team a.mcap", "/explorer/cmd_vel", "10", "10", "9"],
        [str(SCHEMA_VERSION), "runs/team a.mcap", "/tf", "3", "3", "3"],
    ]
