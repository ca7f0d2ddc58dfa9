"""Report formats: the table, JSON, JUnit (a case per rubric line) and CSV (a row per recording)."""

from __future__ import annotations

import csv
import io
import json
import xml.etree.ElementTree as ET

from usar_replay.grade import Check, GradeReport
from usar_replay.reports import to_csv, to_json, to_junit, to_table

T0 = 1_000_000_000


def _report(source: str, *, fail: bool, complete: bool = True) -> GradeReport:
    checks = (
        Check("explorer.target_1", "explorer reached target_1", True, 12, 12, "0.05 m", "<= 0.15 m",
              T0 + 9_400_000_000),
        Check("time_limit", "within the limit", not fail, 0 if fail else 4, 4, "700.0 s",
              "<= 600 s", T0 + 700_000_000_000 if fail else None),
    )  # fmt: skip
    problem = "" if complete else "the file is truncated or corrupt; read 10 messages"
    return GradeReport(source, checks, T0, complete, problem)


def test_table_has_every_line_verdict_and_evidence_time() -> None:
    text = to_table(_report("a.mcap", fail=True))
    lines = text.splitlines()
    assert lines[0] == "Grade of a.mcap"
    row = next(line for line in lines if "time_limit" in line)
    assert row.startswith("FAIL") and "700.0 s" in row and "t=701.0s" in row  # sim time
    assert lines[-1] == "Total: 12 / 16 points: FAIL"
    incomplete = to_table(_report("b.mcap", fail=False, complete=False))
    assert "WARNING: the log is incomplete" in incomplete and "(incomplete log)" in incomplete


def test_junit_one_case_per_line_per_recording_and_errors_kept() -> None:
    reports = [_report("a.mcap", fail=True), _report("b.mcap", fail=False, complete=False)]
    root = ET.fromstring(to_junit(reports, [("c.mcap", "c.mcap: not an MCAP file")]))
    suites = root.findall("testsuite")
    assert [s.get("name") for s in suites] == ["a.mcap", "b.mcap", "c.mcap"]
    assert [tc.get("name") for tc in suites[0]] == ["explorer.target_1", "time_limit"]
    failure = suites[0][1].find("failure")
    assert failure is not None and "700.0 s" in (failure.get("message") or "")
    assert suites[0].get("failures") == "1" and suites[0].get("errors") == "0"
    assert suites[1][0].get("name") == "log.complete"
    assert suites[1].get("errors") == "1"
    assert suites[2][0].get("name") == "log.readable" and suites[2].get("errors") == "1"
    props = {p.get("name"): p.get("value") for p in suites[0][0].iter("property")}
    assert props["evidence_s"] == "10.400" and props["points"] == "12"


def test_csv_one_row_per_recording() -> None:
    reports = [_report("a.mcap", fail=True), _report("b.mcap", fail=False)]
    rows = list(csv.DictReader(io.StringIO(to_csv(reports, [("c.mcap", "bad")]))))
    assert [r["recording"] for r in rows] == ["a.mcap", "b.mcap", "c.mcap"]
    assert [r["time_limit"] for r in rows] == ["fail", "pass", ""]
    assert [r["passed"] for r in rows] == ["0", "1", "0"] and rows[2]["error"] == "bad"


def test_json_round_trips_with_evidence_seconds() -> None:
    data = json.loads(to_json([_report("a.mcap", fail=True)], [("c.mcap", "bad")]))
    assert data[0]["points"] == 12 and data[0]["passed"] is False
    assert [c["evidence_s"] for c in data[0]["checks"]] == [10.4, 701.0]  # sim time
    assert data[1] == {
        "source": "c.mcap",
        "passed": False,
        "error": "bad",
        "log_complete": False,
        "checks": [],
    }
