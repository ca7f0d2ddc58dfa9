"""code/output: the table fits 100 columns; JSON and CSV are versioned and deterministic."""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import codetools

from usar_replay.code.classgrade import grade_class
from usar_replay.code.output import FORMAT, to_csv, to_json, to_text
from usar_replay.code.rubric import default_rubric


def test_the_outputs(tmp_path: Path) -> None:
    codetools.alpha(tmp_path / "c" / "alpha")
    codetools.copy_of_alpha(tmp_path / "c" / "copy")
    codetools.procedural(tmp_path / "c" / "proc")
    done = grade_class([str(tmp_path / "c")], default_rubric())
    doc = json.loads(to_json(done.grades, done.similar, rubric="r", template=None,
                             threshold=done.threshold))  # fmt: skip
    assert doc["format"] == FORMAT == "usar-code/1"
    pkg = doc["packages"][0]
    assert {"package", "path", "points", "max_points", "lines", "metrics"} <= set(pkg)
    assert {"id", "points", "max_points", "measured"} <= set(pkg["lines"][0])
    assert [{k: p[k] for k in ("a", "b")} for p in doc["similar"]] == [{"a": "alpha",
                                                                         "b": "copy"}]
    again = grade_class([str(tmp_path / "c")], default_rubric(), jobs=2)
    assert to_json(again.grades, again.similar, rubric="r", template=None,
                   threshold=again.threshold) == to_json(
        done.grades, done.similar, rubric="r", template=None, threshold=done.threshold)
    rows = list(csv.DictReader(io.StringIO(to_csv(done.grades, done.similar))))
    assert [r["team"] for r in rows] == ["alpha", "copy", "proc"]
    assert rows[0]["format"] == FORMAT and rows[0]["similar_to"] == "copy (0.96)"
    text = to_text(done.grades, done.similar, done.threshold)
    assert all(len(line) <= 100 for line in text.splitlines())
    assert "0.96  alpha ~ copy" in text


def test_a_line_without_a_value_says_why_beside_its_place(tmp_path: Path) -> None:
    """A package that does not compile: its warnings line shows the note and the error's place,
    not a bare place that reads as a warning's."""
    from usar_replay.code.compile import Compiled
    from usar_replay.code.grade import Options, grade
    from usar_replay.code.sources import read_submission

    sub = read_submission(codetools.alpha(tmp_path / "a"))
    broken = Compiled(False, 0, "src/main.cpp:6")
    g = grade(sub, default_rubric(), options=Options(built=broken))
    line = next(x for x in to_text([g], [], 0.6).splitlines() if " builds_clean" in x)
    assert line.split() == ["0/3", "builds_clean", "does", "not", "compile:", "src/main.cpp:6"]


def test_a_team_named_as_a_formula_is_text_in_every_output() -> None:
    """Issue 50, finding 6: a team folder named ``=HYPERLINK(...)`` (controls in it too) is a
    cell that begins with ``'`` in the CSV, escaped in the JSON and the table."""
    from usar_replay.code.grade import refused
    from usar_replay.core.safe_text import safe

    evil = '=HYPERLINK("https:\\\\evil.invalid","open report")\x1b[2J\u202e'
    grades = [refused(evil, f"/c/{evil}", f"{evil}: unreadable", default_rubric()),
              refused("-dash", "/c/-dash", "x", default_rubric())]  # fmt: skip
    text = to_csv(grades, [])
    rows = list(csv.reader(io.StringIO(text)))
    assert [r[1] for r in rows[1:]] == ["'-dash", "'=HYPERLINK(\"https:\\\\evil.invalid\",\"open "
                                        "report\")\\x1b[2J\\u202e"]  # fmt: skip
    assert all(not c.startswith(("=", "+", "-", "@")) for r in rows for c in r)
    doc = to_json(grades, [], rubric="r", template=None, threshold=0.6)
    assert all(safe(ch) == ch or ch == "\n" for ch in doc)
    assert all(safe(ch) == ch for ch in to_text(grades, [], 0.6).replace("\n", ""))
