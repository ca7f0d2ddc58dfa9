"""One submission graded in place for Gradescope: the results file is written before the first
run, after each world and at the end, each time whole; the submission's folder is read where it
lies (never a link) and nothing is written into it."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import pytest
from conftest import one_room

from usar_replay.batch.gradescope import (
    PENDING,
    Autograder,
    error_results,
    grade_submission,
    pending_results,
)
from usar_replay.batch.plan import discover_team, make_worlds
from usar_replay.core.errors import UsageError
from usar_replay.core.limits import GRADESCOPE_LIMITS
from usar_replay.core.settings import RunSettings, to_toml
from usar_replay.sandbox.kernel_sandbox import bwrap_available
from usar_replay.world.scenario_toml import to_toml as scenario_toml

ROOT = Path(__file__).resolve().parents[2]
MINIMAL = (ROOT / "examples" / "minimal_mission.py").read_text(encoding="utf-8")


def _layout(tmp_path: Path) -> Autograder:
    sub = tmp_path / "autograder" / "submission"
    sub.mkdir(parents=True)
    (sub / "mission.py").write_text(MINIMAL, encoding="utf-8")
    return Autograder(sub, tmp_path / "autograder" / "results" / "results.json")


def _files(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in folder.rglob("*") if p.is_file()}


def test_written_early_after_each_world_and_at_the_end(tmp_path: Path) -> None:
    where = _layout(tmp_path)
    before = _files(where.submission)
    rooms = []
    for name in ("room_a", "room_b"):
        rooms.append(tmp_path / f"{name}.toml")
        rooms[-1].write_text(scenario_toml(one_room()), encoding="utf-8")
    worlds = make_worlds((), [str(r) for r in rooms])
    written: list[dict[str, Any]] = []
    final, summary = grade_submission(
        where,
        worlds,
        tmp_path / "work",
        settings_toml=to_toml(RunSettings()),
        limits=GRADESCOPE_LIMITS,
        sandbox=bwrap_available()[0],
        quiet=True,
        on_write=written.append,
    )
    assert not summary.errors
    first, after_one, *_, last = written
    # before any run: 0 of the full marks, every world pending
    assert first["score"] == 0 and first["max_score"] == final["max_score"] > 0
    assert all(PENDING in t["output"] for t in first["tests"])
    assert "grading started; 0 of 2 worlds" in first["output"]
    # after the first world: its points, the other still pending at 0
    graded = [t for t in after_one["tests"] if PENDING not in t["output"]]
    assert [t["name"] for t in graded] == ["room_a: the course rubric"]
    assert after_one["score"] == graded[0]["score"] > 0
    assert "1 of 2 worlds graded so far" in after_one["output"]
    # the end: the batch's own file, its score the sum of the worlds'
    assert last == final and json.loads(where.results.read_text(encoding="utf-8")) == final
    assert final["score"] == pytest.approx(sum(t["score"] for t in final["tests"]))
    assert final["score"] > 0 and len(final["tests"]) == 2
    assert all(PENDING not in t["output"] for t in final["tests"])
    # graded in place: the submission's folder is as it was, the runs' files are in the work dir
    assert _files(where.submission) == before
    assert (tmp_path / "work" / "submission" / "room_a.grade.json").is_file()
    assert not list(where.results.parent.glob("*.tmp*"))  # atomic writes leave nothing behind


def test_pending_results_add_up_to_the_full_marks() -> None:
    worlds = make_worlds((), [])
    got = pending_results(worlds, {"course": 60.0}, "hidden")
    assert (got["score"], got["max_score"]) == (0.0, 60.0)
    assert [t["visibility"] for t in got["tests"]] == ["hidden"]
    assert error_results("no key")["output"] == "usar: error: no key"


def test_the_submission_is_read_in_place_never_through_a_link(tmp_path: Path) -> None:
    where = _layout(tmp_path)
    sub = discover_team(where.submission)
    assert sub.path == where.submission.resolve() and sub.target.endswith("mission.py")
    assert not sub.problem
    link = tmp_path / "link"
    link.symlink_to(where.submission)
    with pytest.raises(UsageError, match="not a folder"):
        discover_team(link)
    with pytest.raises(UsageError, match="not a folder"):
        discover_team(tmp_path / "none")


def test_the_work_folder_is_not_the_submission(tmp_path: Path) -> None:
    where = _layout(tmp_path)
    with pytest.raises(UsageError, match="must not contain each other"):
        grade_submission(
            where, make_worlds((), []), where.submission / "w", settings_toml="", sandbox=False
        )


def test_the_root_comes_from_the_environment(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("USAR_AUTOGRADER", "/tmp/ag")
    got = Autograder.here()
    assert (got.submission, got.results) == (
        Path("/tmp/ag/submission"),
        Path("/tmp/ag/results/results.json"),
    )
    assert Autograder.here("s", "r.json") == Autograder(Path("s"), Path("r.json"))
    monkeypatch.delenv("USAR_AUTOGRADER")
    assert Autograder.here().submission == Path("/autograder/submission")
    assert os.environ.get("USAR_AUTOGRADER") is None
