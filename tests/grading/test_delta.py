"""The rubric delta of ``usar replay`` with other code or settings: only the lines whose verdict
or points change, the totals, and lines that fit 100 columns."""

from __future__ import annotations

from usar_replay.grading.delta import rubric_delta
from usar_replay.grading.verdict import Check, GradeReport


def _check(cid: str, passed: bool, points: float, measured: str = "m") -> Check:
    return Check(cid, "", passed, points, 10.0, measured, "t", None)


def _report(*checks: Check) -> GradeReport:
    return GradeReport("x.mcap", checks, 0)


def test_only_changed_lines_in_rubric_order() -> None:
    before = _report(_check("a", True, 10), _check("b", True, 10), _check("c", False, 0))
    after = _report(
        _check("a", True, 10, measured="moved but still passes"),
        _check("b", False, 0, measured="never"),
        _check("c", True, 10),
    )
    d = rubric_delta(before, after)
    assert [r.id for r in d.rows] == ["b", "c"]
    assert [r.points for r in d.rows] == [-10.0, 10.0]
    assert (d.total_before, d.total_after, d.max_points) == (20.0, 20.0, 30.0)
    lines = d.lines()
    assert lines[0] == "Rubric lines that change (recorded -> replayed):"
    assert lines[1].split() == ["b", "PASS", "10/10", "->", "FAIL", "0/10", "-10", "pts"]
    assert lines[2].strip() == "m -> never"
    assert lines[-1] == "  total 20 -> 20 of 30 (0 pts)"


def test_a_line_only_one_side_has() -> None:
    d = rubric_delta(_report(_check("a", True, 10)), _report(_check("b", False, 0)))
    assert [(r.id, r.before is None, r.after is None) for r in d.rows] == [
        ("a", False, True),
        ("b", True, False),
    ]
    assert "(none)" in d.lines()[1]
    assert d.as_dict()["lines"] == [
        {
            "id": "a",
            "passed_before": True,
            "passed_after": None,
            "points_before": 10.0,
            "points_after": 0.0,
            "points": -10.0,
            "measured_before": "m",
            "measured_after": "",
        },
        {
            "id": "b",
            "passed_before": None,
            "passed_after": False,
            "points_before": 0.0,
            "points_after": 0.0,
            "points": 0.0,
            "measured_before": "",
            "measured_after": "m",
        },
    ]


def test_no_change_says_so_and_long_lines_fit() -> None:
    same = _report(_check("a", True, 10))
    assert rubric_delta(same, same).lines() == [
        "Rubric: no line changes.",
        "  total 10 -> 10 of 10 (0 pts)",
    ]
    long = "x" * 150
    d = rubric_delta(
        _report(_check("l" * 70, True, 10, measured=long)),
        _report(_check("l" * 70, False, 0, measured=long)),
    )
    assert all(len(line) <= 100 for line in d.lines()), d.lines()
