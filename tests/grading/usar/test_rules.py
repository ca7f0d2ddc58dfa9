"""The TA's rules as data: each with its question and source, and each rubric line names the
one it applied."""

from __future__ import annotations

from rubric_streams import good_run, world

from usar_replay.grading.usar import RUBRIC, RUBRIC_VERSION, RULES, Grader, judge


def test_every_rule_has_a_question_and_a_source() -> None:
    for key, rule in RULES.items():
        assert rule.question and rule.says and rule.source, key
        assert rule.question.startswith("Q") or rule.question == "(no points)", key
        assert len(rule.says) <= 100, key  # it is shown with the line
    assert RUBRIC_VERSION == RUBRIC.version == 4


def test_every_line_says_its_rule() -> None:
    g = Grader(world())
    good_run(g)
    texts = {r.text for r in RULES.values()}
    for line in judge(g):
        assert line.rule in texts, line.id
    by_id = {c.id: c.rule for c in judge(g)}
    assert by_id["follower.marker_0"] == RULES["visits"].text
    assert "0.4m seems to be good" in by_id["follower.marker_0"]
