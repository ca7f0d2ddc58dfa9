"""code/rubric: the rubric is data; lines score linearly between their thresholds."""

from __future__ import annotations

from pathlib import Path

import pytest

from usar_replay.code.rubric import FORMAT, default_rubric, load, parse, score
from usar_replay.core.errors import UsageError


def test_the_default_rubric_is_the_courses_60_points() -> None:
    r = default_rubric()
    assert r.max_points == 60
    assert all(line.source for line in r.lines), "every line says where its threshold is from"
    assert any("design quality" in g for g in r.grader)


def _one(kind: str, **extra: object) -> str:
    more = "".join(
        f"{k} = {{ doc = 1.0, elsewhere = 0.5 }}\n" if isinstance(v, dict) else f"{k} = {v!r}\n"
        for k, v in extra.items()
    )
    return (f'format = "{FORMAT}"\n[[line]]\nid = "x"\npoints = 10\nmetric = "m"\n'
            f'kind = "{kind}"\n{more}')  # fmt: skip


def test_each_kind_scores() -> None:
    at_most = parse(_one("at_most", full=5, zero=30), "t")
    got = [score(at_most, {"m": v}, {}, {})[0].points for v in (0, 5, 17.5, 30, 99)]
    assert got == [10, 10, 5, 0, 0]
    at_least = parse(_one("at_least", full=0.8, zero=0.0), "t")
    assert score(at_least, {"m": 0.4}, {}, {})[0].points == 5
    true = parse(_one("true"), "t")
    assert [score(true, {"m": v}, {}, {})[0].points for v in (True, False)] == [10, 0]
    levels = parse(_one("levels", levels={}), "t")
    assert [score(levels, {"m": v}, {}, {})[0].points for v in ("doc", "elsewhere", "no")] == [
        10, 5, 0
    ]  # fmt: skip


def test_a_metric_not_measured_scores_nothing_and_says_why() -> None:
    r = parse(_one("true"), "t")
    got = score(r, {"m": None}, {}, {"m": "doxygen is not installed: apt-get install doxygen"})[0]
    assert got.points is None and "apt-get install doxygen" in got.note
    assert score(r, {}, {}, {})[0].note == "m was not measured"


def test_bad_rubrics_are_one_line_errors(tmp_path: Path) -> None:
    with pytest.raises(UsageError, match="format must be"):
        parse("[[line]]\n", "t")
    with pytest.raises(UsageError, match="kind 'most'"):
        parse(_one("most"), "t")
    with pytest.raises(UsageError, match="full and zero are both"):
        parse(_one("at_most", full=1, zero=1), "t")
    with pytest.raises(UsageError, match="not TOML"):
        parse("= =", "t")
    with pytest.raises(UsageError, match="cannot be read"):
        load(str(tmp_path / "none.toml"))
    (tmp_path / "r.toml").write_text(_one("true"))
    assert load(str(tmp_path / "r.toml")).max_points == 10
