"""code/classgrade: teams found in the paths, each graded, copies listed, bad folders said."""

from __future__ import annotations

import os
from pathlib import Path

import codetools
import pytest

from usar_replay.code.classgrade import grade_class, teams
from usar_replay.code.rubric import default_rubric
from usar_replay.code.template import read_template
from usar_replay.core.errors import UsageError
from usar_replay.core.folder_walk import linked


def _class(root: Path) -> Path:
    for name in ("alpha", "copy_of_alpha", "beta", "procedural", "borrowed"):
        getattr(codetools, name)(root / name)
    return root


def test_a_class_folder_is_its_teams(tmp_path: Path) -> None:
    root = _class(tmp_path / "class")
    (root / "_notes").mkdir()
    got = [name for name, _ in teams([str(root)])]
    assert got == ["alpha", "beta", "borrowed", "copy_of_alpha", "procedural"]
    assert [n for n, _ in teams([str(root / "beta"), str(root / "alpha")])] == ["alpha", "beta"]
    with pytest.raises(UsageError, match="no such folder"):
        teams([str(tmp_path / "none")])


def test_the_copy_is_listed_and_the_honest_pairs_are_not(tmp_path: Path) -> None:
    root = _class(tmp_path / "class")
    tmpl = read_template(codetools.template(tmp_path / "tmpl"))
    done = grade_class([str(root)], default_rubric(), tmpl, jobs=2)
    assert [(p.a, p.b) for p in done.similar] == [("alpha", "copy_of_alpha")]
    assert [g.team for g in done.grades] == sorted(g.team for g in done.grades)


def test_a_team_with_a_fifo_is_its_verdict_not_the_end(tmp_path: Path) -> None:
    root = tmp_path / "class"
    codetools.alpha(root / "alpha")
    codetools.beta(root / "bad")
    os.mkfifo(root / "bad" / "src" / "x.cpp")
    done = grade_class([str(root)], default_rubric())
    verdicts = {g.team: g.verdict for g in done.grades}
    assert verdicts == {"alpha": "graded", "bad": "unreadable"}
    bad = next(g for g in done.grades if g.team == "bad")
    assert "not a regular file" in bad.findings[0]


def test_a_class_where_one_team_has_no_package_is_still_a_class(tmp_path: Path) -> None:
    root = tmp_path / "class"
    codetools.alpha(root / "alpha")
    codetools.beta(root / "beta")
    (root / "python_team").mkdir()
    (root / "python_team" / "mission.py").write_text("def main() -> None: ...\n")
    assert [n for n, _ in teams([str(root)])] == ["alpha", "beta", "python_team"]
    repo = tmp_path / "repo"
    codetools.alpha(repo / "catkin_ws" / "src" / "final_project")
    (repo / "docs").mkdir()
    assert teams([str(repo)]) == [("repo", repo)]


def test_a_linked_team_folder_is_its_verdict_in_the_batchs_words(tmp_path: Path) -> None:
    """A class folder's team that is a link is never read through (it could lead anywhere):
    that team's verdict, saying so in the words ``usar batch`` uses; a path given on the
    command line is the grader's own, read where it leads."""
    real = tmp_path / "real"
    codetools.alpha(real / "elsewhere")
    root = tmp_path / "class"
    codetools.alpha(root / "alpha")
    codetools.beta(root / "beta")
    (root / "linked").symlink_to(real / "elsewhere")
    assert [n for n, _ in teams([str(root)])] == ["alpha", "beta", "linked"]
    done = grade_class([str(root)], default_rubric())
    bad = next(g for g in done.grades if g.team == "linked")
    assert bad.verdict == "unreadable" and bad.points == 0
    assert bad.findings == (linked(["linked"]),)
    assert bad.findings[0].startswith("linked is a link: usar reads only real folders")
    assert teams([str(root / "linked")]) == [("elsewhere", (real / "elsewhere").resolve())]
    only_links = tmp_path / "links"
    only_links.mkdir()
    (only_links / "a").symlink_to(root / "alpha")
    (only_links / "b").symlink_to(root / "beta")
    with pytest.raises(UsageError, match=r"links: a, b are links: usar reads only real folders"):
        teams([str(only_links)])


def test_a_committed_catkin_workspace_is_graded_without_catkins_link(tmp_path: Path) -> None:
    """Every ``catkin_make`` workspace has ``src/CMakeLists.txt`` -> catkin's
    ``toplevel.cmake``: catkin's link, left out and said; the team is graded on the rest, as
    ``usar batch`` reads it; any other link out is still the team's verdict (issue 51)."""
    root = _class(tmp_path / "class")
    ws = tmp_path / "class" / "workspace"
    (ws / "src").mkdir(parents=True)
    os.rename(root / "beta", ws / "src" / "beta")
    (ws / "src" / "CMakeLists.txt").symlink_to("/opt/ros/noetic/share/catkin/cmake/toplevel.cmake")
    done = grade_class([str(root)], default_rubric(), jobs=2)
    [team] = [g for g in done.grades if g.team == "workspace"]
    assert team.verdict == "graded" and team.points > 0
    assert "src/CMakeLists.txt: catkin's link out of the workspace, left out" in team.findings
    (ws / "src" / "CMakeLists.txt").unlink()
    (ws / "src" / "CMakeLists.txt").symlink_to("/etc/hostname")
    done = grade_class([str(root)], default_rubric(), jobs=2)
    [team] = [g for g in done.grades if g.team == "workspace"]
    assert team.verdict == "unreadable" and "a link leaving" in team.findings[0]
