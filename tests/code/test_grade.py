"""code/grade: every metric the JSON promises, each rubric line with its evidence."""

from __future__ import annotations

import shutil
from pathlib import Path

import codetools
import pytest

from usar_replay.code.compile import Compiled
from usar_replay.code.grade import Options, PackageGrade, grade, refused
from usar_replay.code.rubric import default_rubric
from usar_replay.code.sources import read_submission
from usar_replay.code.template import read_template

pytestmark = pytest.mark.skipif(
    any(shutil.which(t) is None for t in ("doxygen", "cppcheck", "clang-format")),
    reason="needs doxygen, cppcheck, clang-format",
)
METRICS = {"doc_coverage", "docs_own", "commented_out_lines", "largest_commented_block",
           "unused_functions", "classes", "main_lines", "compiles", "builds_clean",
           "report_pages"}  # fmt: skip


def test_a_good_package_gets_every_measured_point(tmp_path: Path) -> None:
    g = grade(read_submission(codetools.alpha(tmp_path / "a")), default_rubric())
    assert set(g.metrics) >= METRICS
    assert g.metrics["docs_own"] is True and g.metrics["classes"] == 2
    assert g.metrics["main_lines"] == 14 and g.metrics["doc_coverage"] == 1.0
    assert g.points == g.max_points == 57  # builds_clean not measured without --compile
    line = {s.line.id: s for s in g.lines}["builds_clean"]
    assert line.points is None and "--compile" in line.note


def test_a_procedural_package_loses_the_oop_and_unused_code_lines(tmp_path: Path) -> None:
    g = grade(read_submission(codetools.procedural(tmp_path / "p")), default_rubric())
    by = {s.line.id: s for s in g.lines}
    assert by["classes"].points == 0 and by["classes"].measured == 0
    assert by["unused_functions"].measured == 3
    assert by["unused_functions"].evidence.startswith("src/main.cpp:6 helper_two")
    assert by["commented_block"].measured == 6
    assert by["commented_block"].points == 0  # 6 lines: the worst real package's block
    assert by["commented_block"].evidence == "src/main.cpp:18"
    assert by["doc_coverage"].points == 0


def test_borrowed_html_scores_no_docs_points_and_says_so(tmp_path: Path) -> None:
    g = grade(read_submission(codetools.borrowed(tmp_path / "b")), default_rubric())
    by = {s.line.id: s for s in g.lines}
    assert g.metrics["docs_own"] is False and by["docs_html"].points == 0
    assert "not documented there" in by["docs_html"].evidence


def test_the_templates_code_is_not_the_teams(tmp_path: Path) -> None:
    team = codetools.package(tmp_path / "t", "final_project",
                             {"src/main.cpp": codetools.TEMPLATE_MAIN})  # fmt: skip
    tmpl = read_template(codetools.template(tmp_path / "tmpl"))
    alone = grade(read_submission(team), default_rubric())
    with_t = grade(read_submission(team), default_rubric(), tmpl)
    assert alone.metrics["commented_out_lines"] == 4
    assert with_t.metrics["commented_out_lines"] == 0
    assert with_t.metrics["doc_coverage"] is None  # nothing of its own to document


def test_compile_is_measured_when_asked(tmp_path: Path) -> None:
    pkg = codetools.package(tmp_path / "c", "c", {"src/a.cpp": "int main() { int x; }\n"})
    g = grade(read_submission(pkg), default_rubric(), options=Options(compile=True))
    assert (g.metrics["compiles"], g.metrics["builds_clean"]) == (True, False)
    assert g.metrics["compiler_warnings"] >= 1


def test_the_demos_build_is_scored_instead_when_given(tmp_path: Path) -> None:
    """``usar batch --code``: the build's answer is the line's, with its note; out of 60."""
    sub = read_submission(codetools.alpha(tmp_path / "a"))
    warned = Compiled(True, 2, "src/main.cpp:9; src/x.cpp:3", note="the demo's catkin_make")
    g = grade(sub, default_rubric(), options=Options(built=warned))
    line = {s.line.id: s for s in g.lines}["builds_clean"]
    assert (line.points, line.measured, line.evidence) == (2.54, 2, warned.where)  # 3 * 11/13
    assert line.note == "the demo's catkin_make" and g.max_points == 60
    assert (g.metrics["compiles"], g.metrics["compiler_warnings"]) == (True, 2)

    def built(c: Compiled) -> PackageGrade:
        return grade(sub, default_rubric(), options=Options(built=c))

    clean = built(Compiled(True, 0, ""))
    assert clean.points == clean.max_points == 60
    broken = built(Compiled(False, 0, "CMakeLists.txt:3"))
    assert broken.metrics["compiles"] is False and broken.max_points == 60
    gone = {s.line.id: s for s in broken.lines}["builds_clean"]
    assert (gone.points, gone.note) == (0.0, "does not compile")  # no warnings: not clean
    unknown = built(Compiled(None, 0, "", "not built"))
    assert unknown.max_points == 57
    assert {s.line.id: s for s in unknown.lines}["builds_clean"].note == "not built"


def test_a_refused_team_scores_zero_and_says_why() -> None:
    g = refused("t", "/x", "src/p.cpp: not a regular file", default_rubric())
    assert g.verdict == "unreadable" and g.points == 0 and g.max_points == 60
    assert all(s.note == "src/p.cpp: not a regular file" for s in g.lines)


def test_a_tool_stopped_by_the_teams_files_scores_zero_not_null(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A file made to hang doxygen must not take its lines out of the maximum."""
    import usar_replay.code.doxygen as dox
    from usar_replay.code.tools import Ran

    def stopped(*_a: object, **_k: object) -> Ran:
        return Ran(-9, "", "", "its 30 s wall limit")

    monkeypatch.setattr(dox, "run_tool", stopped)
    g = grade(read_submission(codetools.alpha(tmp_path / "a")), default_rubric())
    by = {s.line.id: s for s in g.lines}
    assert by["doc_coverage"].points == 0 and by["classes"].points == 0
    assert by["doc_coverage"].note == "doxygen exceeded its 30 s wall limit"
    assert g.max_points == 57


def test_a_package_without_cxx_scores_no_code_points(tmp_path: Path) -> None:
    """Nothing to measure is not clean code: no unused functions of nothing."""
    pkg = codetools.package(tmp_path / "e", "e", {"doc/instructions.txt": "roslaunch e e\n"})
    g = grade(read_submission(pkg), default_rubric())
    by = {s.line.id: s for s in g.lines}
    assert by["unused_functions"].points == 0 and by["formatting"].points == 0
    assert by["unused_functions"].note == "no readable C++ sources in the package"
    assert by["instructions"].points == 4 and g.points == 4 and g.max_points == 60
