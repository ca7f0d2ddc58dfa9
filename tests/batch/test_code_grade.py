"""batch/code_grade: ``usar batch --code`` grades each team's code beside its demo, in the
class's table, CSV, page and Gradescope results (a test of its own, its own max_score)."""

from __future__ import annotations

import csv
import io
import json
import shutil
from dataclasses import replace
from pathlib import Path

import codetools
import pytest

from usar_replay.batch.classpage import class_page
from usar_replay.batch.classreport import (
    CLASS_FILE,
    class_json,
    collect,
    from_folder,
    gradescope_results,
    to_csv,
    to_table,
)
from usar_replay.batch.code_grade import CODE_JSON, CodeCell, cells_from_json, grade_code
from usar_replay.batch.plan import GRADE_FORMAT, Plan, Submission, make_worlds

needs = pytest.mark.skipif(
    any(shutil.which(t) is None for t in ("doxygen", "cppcheck", "clang-format")),
    reason="needs the code grade's tools",
)


def _class(tmp_path: Path) -> tuple[Plan, list[tuple[str, Path]]]:
    subs = tmp_path / "subs"
    codetools.alpha(subs / "alpha")
    codetools.copy_of_alpha(subs / "copy")
    (subs / "py").mkdir(parents=True)
    (subs / "py" / "mission.py").write_text("def main() -> None:\n    pass\n")
    out = tmp_path / "out"
    teams = [("alpha", subs / "alpha"), ("copy", subs / "copy"), ("py", subs / "py")]
    world = replace(make_worlds((), (), None)[0], name="w")  # the course world
    plan = Plan(out, [Submission(t, p, "", "", "") for t, p in teams], [world])
    for team, _ in teams:
        (out / team).mkdir(parents=True)
        grade = {"format": GRADE_FORMAT, "outcome": "done", "points": 60.0, "max_points": 60.0}
        (out / team / "w.grade.json").write_text(json.dumps(grade))
    return plan, teams


@needs
def test_the_code_grade_beside_the_demo(tmp_path: Path) -> None:
    plan, teams = _class(tmp_path)
    code = grade_code(teams, plan.out_root, None)
    assert set(code) == {"alpha", "copy"}  # a Python mission has no package: no code grade
    assert code["alpha"].points == code["alpha"].max_points == 57
    assert code["alpha"].similar == ("copy (0.96)",)
    for name in ("code.json", "code.csv", "code.html"):
        assert (plan.out_root / name).is_file()
    grades = replace(collect(plan, {"w": 60.0}), code=code)

    rows = list(csv.DictReader(io.StringIO(to_csv(grades))))
    assert [(r["team"], r["total"], r["code"], r["code_max"]) for r in rows] == [
        ("alpha", "60", "57", "57"), ("copy", "60", "45", "57"), ("py", "60", "", "")
    ]  # fmt: skip
    table = to_table(grades)
    assert "  alpha: 57/57; similar to copy (0.96) (see code.html)" in table
    assert "  py: no catkin package" in table

    results = gradescope_results(grades, "copy", {"w": "w"}, execution_time_s=1.0)
    demo, code_test = results["tests"]
    assert (demo["score"], demo["max_score"]) == (60.0, 60.0)
    assert code_test["name"] == "code submission: the code rubric"
    assert (code_test["score"], code_test["max_score"]) == (45.0, 57.0)
    assert "Similar to (for a person to review, never points): alpha (0.96)" in code_test["output"]
    assert (results["score"], results["max_score"]) == (105.0, 117.0)

    page = class_page(grades, lambda _t, _w: None)
    assert "<th>code</th>" in page and "<a href='code.html'>similar to copy (0.96)</a>" in page
    # `usar report OUT` rebuilds the class from the folder: the code grades come back
    (plan.out_root / CLASS_FILE).write_text(class_json(grades))
    back = from_folder(plan.out_root)
    assert back is not None and back.code == code


@needs
def test_a_team_of_long_pdfs_holds_the_others_no_longer_than_its_budget(tmp_path: Path) -> None:
    """Six PDFs of 1,500 pages in a team's doc/ (issue 50: the batch's code grade took 108 s
    against 12 s): that team is graded within its budget, its verdict line in code.json, and
    every other team's grade is written with it."""
    import time

    from usar_replay.code.budget import DEFAULT

    plan, teams = _class(tmp_path)
    for n in range(6):
        codetools.many_pages_pdf(teams[1][1] / "doc" / f"part{n}.pdf", 1500)
    start = time.monotonic()
    code = grade_code(teams, plan.out_root, None, jobs=2)
    assert time.monotonic() - start < DEFAULT.wall_s
    assert set(code) == {"alpha", "copy"}
    doc = json.loads((plan.out_root / CODE_JSON).read_text())
    findings = {p["team"]: p["findings"] for p in doc["packages"]}
    assert findings["copy"][0].startswith(f"budget spent: its {DEFAULT.pdfs} PDFs tried")
    assert not findings["alpha"]


def test_without_code_nothing_changes(tmp_path: Path) -> None:
    plan, _ = _class(tmp_path)
    grades = collect(plan, {"w": 60.0})
    assert grades.code == {}
    assert "code" not in to_csv(grades).splitlines()[0].split(",")
    assert "code submission" not in to_table(grades)
    assert len(gradescope_results(grades, "alpha", {}, execution_time_s=0)["tests"]) == 1


def test_cells_from_json_reads_only_its_format() -> None:
    doc = {"format": "usar-code/1", "similar": [{"a": "a", "b": "b", "score": 0.7}],
           "packages": [{"team": "a", "points": 3, "max_points": 6,
                         "lines": [{"id": "x", "points": 3, "max_points": 6, "measured": 1,
                                    "evidence": "a.cpp:1"}]}]}  # fmt: skip
    assert cells_from_json(doc) == {"a": CodeCell(3.0, 6.0, ("3/6 x = 1  a.cpp:1",), ("b (0.70)",))}
    assert cells_from_json({"format": "other"}) == {} and cells_from_json(None) == {}
    assert CODE_JSON == "code.json"


@needs
def test_the_driver_writes_the_code_grade_with_code(tmp_path: Path) -> None:
    """``grade_class(..., code=True)`` (what ``usar batch --code`` calls) after the runs."""
    from usar_replay.batch.driver import grade_class
    from usar_replay.batch.engines import make_engine

    plan, _ = _class(tmp_path)
    tmpl = codetools.template(tmp_path / "template")
    summary = grade_class(plan, make_engine("local", 1), gradescope=True, quiet=True,
                          code=True, code_template=str(tmpl))  # fmt: skip
    assert "code submission (usar code" in summary.table
    doc = json.loads((plan.out_root / "code.json").read_text())
    assert doc["template"] == str(tmpl)
    results = json.loads((plan.out_root / "alpha" / "results.json").read_text())
    assert [t["name"] for t in results["tests"]][-1] == "code submission: the code rubric"
    assert "code_max" in (plan.out_root / "summary.csv").read_text().splitlines()[0]


def test_a_code_template_without_code_is_a_usage_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from usar_replay.cli.main import main

    (tmp_path / "subs").mkdir()
    args = ["batch", str(tmp_path / "subs"), "-o", str(tmp_path / "out")]
    assert main([*args, "--code-template", str(tmp_path)]) == 2
    assert "--code-template: give --code too" in capsys.readouterr().err
    assert main([*args, "--code", "--code-template", str(tmp_path / "none")]) == 2
    assert "--code-template " in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_a_runs_record_keeps_what_its_build_said(tmp_path: Path) -> None:
    """compiler_record (what run_one writes) and demo_builds (what the code grade reads): the
    first world by name with one; a hand-edited entry is not one."""
    from usar_replay.batch.code_grade import COMPILER, compiler_record, demo_builds
    from usar_replay.batch.plan import RUN_FORMAT
    from usar_replay.code.compile import Compiled
    from usar_replay.pipeline.record import BuildLog

    root = "/ros1/ws/src/p"
    warned = BuildLog(f"{root}/src/a.cpp:2:5: warning: unused [-Wunused]\n", root, False, ("-W",))
    assert compiler_record("cached", warned, "") == {
        "compiles": True, "warnings": 1, "where": "src/a.cpp:2", "problem": "",
        "note": "the demo's catkin_make (-W added)",
    }  # fmt: skip
    refused = compiler_record("failed", None, "the mission build failed: a link leaving it")
    assert refused is not None and refused["compiles"] is False
    assert refused["note"] == "the demo's build failed: the mission build failed: a link leaving it"
    assert compiler_record("", None, "") is None  # nothing built (a Python mission)
    team = tmp_path / "t"
    team.mkdir()
    record = {"format": RUN_FORMAT, COMPILER: compiler_record("cached", warned, "")}
    (team / "b.run.json").write_text(json.dumps(record))
    (team / "a.run.json").write_text(json.dumps({"format": RUN_FORMAT, COMPILER: {"x": 1}}))
    (team / "c.run.json").write_text(json.dumps({**record, COMPILER: {"compiles": "yes"}}))
    got = demo_builds(tmp_path, ["t", "none"], ["c", "b", "a"])
    assert got == {"t": Compiled(True, 1, "src/a.cpp:2", note="the demo's catkin_make (-W added)")}


@needs
@pytest.mark.usefixtures("own_build_cache")  # the builds in a cache of this module's own
def test_usar_batch_code_scores_the_demos_own_build(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The real path: ``usar batch --code`` builds each C++ package for its demo (catkin_make,
    -Wall -Wextra added) and the code grade reads that build: a warning in the team's own file
    is builds_clean false with its place, a clean build true, a failed build compiles false;
    the code grade is out of 60."""
    from catkintools import cxx_package
    from conftest import one_room

    from usar_replay.cli.main import main
    from usar_replay.world.scenario_toml import save

    subs = tmp_path / "subs"
    cxx_package(subs / "clean", "clean")
    cxx_package(subs / "warned", "warned", "\n  int unused = 3;")
    cxx_package(subs / "broken", "broken", "\n  return nope;")
    world = tmp_path / "room.toml"
    save(one_room(), world)
    out = tmp_path / "out"
    args = ["batch", str(subs), "-o", str(out), "--scenario", str(world), "--code", "--quiet"]
    code = main([*args, "--max-sim-time", "2"])
    said = capsys.readouterr()
    assert code == 0, said.out + said.err
    doc = json.loads((out / CODE_JSON).read_text())
    packages = {p["team"]: p for p in doc["packages"]}
    lines = {t: {x["id"]: x for x in p["lines"]} for t, p in packages.items()}
    assert {t: p["max_points"] for t, p in packages.items()} == {
        "broken": 60, "clean": 60, "warned": 60
    }  # fmt: skip
    clean, warned, broken = (packages[t]["metrics"] for t in ("clean", "warned", "broken"))
    assert (clean["compiles"], clean["builds_clean"], clean["compiler_warnings"]) == (True, True, 0)
    assert lines["clean"]["builds_clean"]["points"] == 3
    assert lines["clean"]["builds_clean"]["note"] == "the demo's catkin_make (-Wall -Wextra added)"
    assert (warned["compiles"], warned["builds_clean"]) == (True, False)
    assert warned["compiler_warnings"] >= 1
    assert lines["warned"]["builds_clean"]["evidence"] == "src/main.cpp:6"
    n = warned["compiler_warnings"]  # graded: full without a warning, none at 13
    assert lines["warned"]["builds_clean"]["points"] == round(3 * (13 - n) / 13, 2) < 3
    assert (broken["compiles"], broken["builds_clean"]) == (False, False)
    assert broken["compiler_warnings"] is None  # not counted: it does not compile
    assert lines["broken"]["builds_clean"]["evidence"] == "src/main.cpp:6"
    assert lines["broken"]["builds_clean"]["points"] == 0
    assert lines["broken"]["builds_clean"]["note"].startswith("does not compile")
    assert json.loads((out / "broken" / "room.run.json").read_text())["outcome"] == "build_failed"
