"""Report formats: the table (fits the terminal), JSON (schema v1), JUnit and CSV."""

from __future__ import annotations

import csv
import io
import json
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from usar_replay.core.settings import Thresholds
from usar_replay.grading.grade import Check, GradeReport
from usar_replay.grading.reports import (
    SCHEMA_VERSION,
    summary_line,
    to_csv,
    to_json,
    to_junit,
    to_table,
)
from usar_replay.grading.usar import RUBRIC_VERSION

T0 = 1_000_000_000


def _report(source: str, *, fail: bool, complete: bool = True) -> GradeReport:
    checks = (
        Check("explorer.target_1", "explorer reached target_1", True, 12, 12,
              "reached at 10.4 s (closest 0.050 m)", "<= 0.15 m", T0 + 9_400_000_000,
              value=0.05, unit="m", limit=0.15, op="<=", evidence="reached"),
        Check("time_limit", "within the limit", not fail, 0 if fail else 4, 4,
              "700.0 s" if fail else "not completed (follower never home)",
              "<= 600 s", T0 + 700_000_000_000 if fail else None,
              value=700.0 if fail else None, unit="s", limit=600.0, op="<=",
              evidence="follower home" if fail else ""),
    )  # fmt: skip
    problem = "" if complete else "the file is truncated or corrupt; read 10 messages"
    return GradeReport(
        source, checks, T0, complete, problem, thresholds=Thresholds(time_limit_s=600.0),
        scenario="course", seconds=0.25, rubric="usar", rubric_version=RUBRIC_VERSION,
    )  # fmt: skip


def test_table_has_every_line_verdict_and_evidence_time() -> None:
    text = to_table(_report("a.mcap", fail=True), width=100)
    lines = text.splitlines()
    assert lines[0] == "Grade of a.mcap"
    row = next(line for line in lines if "time_limit" in line)
    assert row.startswith("FAIL") and "700.0 s" in row and row.endswith("701.0 s")  # sim time
    assert "Total: 12 / 16 points: FAIL" in lines
    incomplete = to_table(_report("b.mcap", fail=False, complete=False), width=100)
    assert "WARNING: the log is incomplete" in incomplete and "(incomplete log)" in incomplete
    never = next(line for line in incomplete.splitlines() if "time_limit" in line)
    assert never.rstrip().endswith("never home)")  # nothing happened: no evidence time


@pytest.mark.parametrize("columns", ["80", "100", "250"])
def test_table_fits_the_terminal(columns: str, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("COLUMNS", columns)
    text = to_table(_report("runs/" + "x" * 120 + ".mcap", fail=True, complete=False))
    assert max(len(line) for line in text.splitlines()[1:]) <= min(int(columns), 100)
    assert "needs <= 600 s" in text
    assert len(summary_line(_report("y" * 200, fail=True), "y" * 200)) <= min(int(columns), 100)


def test_junit_one_case_per_line_per_recording_totals_and_errors_kept() -> None:
    reports = [_report("runs/a.1.mcap", fail=True), _report("b.mcap", fail=False, complete=False)]
    root = ET.fromstring(to_junit(reports, [("c.mcap", "c.mcap: not an MCAP file")]))
    assert (root.get("tests"), root.get("failures"), root.get("errors")) == ("6", "1", "2")
    assert root.get("time") == "0.500"
    suites = root.findall("testsuite")
    assert [s.get("name") for s in suites] == ["runs/a.1.mcap", "b.mcap", "c.mcap"]
    cases = suites[0].findall("testcase")
    assert [tc.get("name") for tc in cases] == ["explorer.target_1", "time_limit"]
    assert cases[0].get("classname") == "usar.grade.a_1" and cases[0].get("time") == "0"
    failure = cases[1].find("failure")
    assert failure is not None and "700.0 s" in (failure.get("message") or "")
    assert suites[0].get("failures") == "1" and suites[0].get("errors") == "0"
    assert suites[0].get("time") == "0.250"
    assert suites[1].findall("testcase")[0].get("name") == "log.complete"
    assert suites[1].get("errors") == "1"
    assert suites[2].findall("testcase")[0].get("name") == "log.readable"
    assert suites[2].get("errors") == "1"
    props = {p.get("name"): p.get("value") for p in cases[0].iter("property")}
    assert props["evidence_s"] == "10.400" and props["points"] == "12"
    assert props["measured_value"] == "0.05" and props["unit"] == "m"
    suite_props = {p.get("name"): p.get("value") for p in suites[0].find("properties") or []}
    assert suite_props["schema_version"] == str(SCHEMA_VERSION)
    assert suite_props["threshold.time_limit_s"] == "600"
    assert (suite_props["rubric"], suite_props["rubric_version"]) == ("usar", str(RUBRIC_VERSION))


def test_csv_one_row_per_recording() -> None:
    reports = [_report("a.mcap", fail=True), _report("b.mcap", fail=False)]
    rows = list(csv.DictReader(io.StringIO(to_csv(reports, [("c.mcap", "bad")]))))
    assert [r["recording"] for r in rows] == ["a.mcap", "b.mcap", "c.mcap"]
    assert [r["time_limit"] for r in rows] == ["fail", "pass", ""]
    assert [r["status"] for r in rows] == ["graded", "graded", "error"]
    assert [r["passed"] for r in rows] == ["0", "1", "0"] and rows[2]["error"] == "bad"
    assert {r["schema_version"] for r in rows} == {str(SCHEMA_VERSION)}


def test_json_schema_numbers_units_and_one_shape() -> None:
    doc = json.loads(to_json([_report("a.mcap", fail=True)], [("c.mcap", "bad")]))
    assert doc["schema_version"] == SCHEMA_VERSION and doc["tool"] == "usar-replay"
    assert doc["tool_version"]
    graded, error = doc["recordings"]
    assert set(graded) == set(error)  # one shape for graded and ungraded entries
    assert graded["points"] == 12 and graded["passed"] is False and graded["status"] == "graded"
    assert graded["thresholds"]["time_limit_s"] == {"value": 600.0, "unit": "s"}
    assert graded["thresholds"]["home_m"] == {"value": 0.15, "unit": "m"}
    line = graded["checks"][1]
    assert line["measured"] == {"value": 700.0, "unit": "s", "text": "700.0 s"}
    assert line["threshold"] == {"value": 600.0, "unit": "s", "op": "<=", "text": "<= 600 s"}
    assert line["evidence"] == {"sim_time_s": 701.0, "what": "follower home"}
    assert [c["evidence"]["sim_time_s"] for c in graded["checks"]] == [10.4, 701.0]
    assert error["status"] == "error" and error["error"] == "bad" and error["checks"] == []
    assert error["points"] is None and error["passed"] is False
    assert (graded["rubric"], graded["rubric_version"]) == ("usar", RUBRIC_VERSION)
    assert error["rubric"] is None and error["rubric_version"] is None


def test_a_grade_says_which_rubric_version_judged_it() -> None:
    """The version changes whenever a line's meaning does (docs/reports.md lists them): the
    usar rubric is at 2 since issue #32 (broadcasts of any frame name, a camera period late)."""
    from usar_replay.grading.rubric_ros2 import RUBRIC as ROS2
    from usar_replay.grading.usar import RUBRIC as USAR

    assert RUBRIC_VERSION == USAR.version == 4 and ROS2.version == 1
    docs = (Path(__file__).resolve().parents[2] / "docs" / "reports.md").read_text()
    assert f"| `usar` | {RUBRIC_VERSION} |" in docs and f"| `ros2-final` | {ROS2.version} |" in docs
