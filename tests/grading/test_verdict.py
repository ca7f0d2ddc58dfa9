"""grading/verdict: a report's totals and lookups over its checks."""

from __future__ import annotations

import pytest

from usar_replay.grading.verdict import Check, GradeReport


def _check(cid: str, passed: bool, points: float, max_points: float) -> Check:
    return Check(cid, f"{cid} line", passed, points, max_points, "m", "t", None)


def test_points_and_the_verdict_add_up_over_the_checks() -> None:
    report = GradeReport(
        source="a.mcap",
        checks=(_check("a", True, 10, 10), _check("b", False, 2.5, 5), _check("c", False, 0, 0)),
        start_ns=0,
    )
    assert (report.points, report.max_points) == (12.5, 15)
    assert not report.passed
    assert report.failed_ids() == ["b", "c"]
    assert report.check("b").points == 2.5
    with pytest.raises(KeyError):
        report.check("z")


def test_an_all_pass_report_and_an_empty_one() -> None:
    ok = GradeReport(source="a", checks=(_check("a", True, 1, 1),), start_ns=5)
    assert ok.passed and ok.failed_ids() == []
    empty = GradeReport(source="a", checks=(), start_ns=0)
    assert empty.passed and empty.points == 0 and empty.max_points == 0
