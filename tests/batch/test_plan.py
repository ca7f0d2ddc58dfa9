"""batch/plan: teams found in a real submissions folder, worlds, and which runs a resume does
again, judged from the files a batch leaves (written here by hand)."""

from __future__ import annotations

import json
import os
from dataclasses import replace
from pathlib import Path

import pytest

from usar_replay.batch import plan as p
from usar_replay.core.errors import UsageError
from usar_replay.core.folder_walk import linked


def _subs(root: Path) -> Path:
    root.mkdir()
    (root / "alpha.py").write_text("def main(): pass\n", encoding="utf-8")
    (root / "beta").mkdir()
    (root / "beta" / "mission.py").write_text("def main(): pass\n", encoding="utf-8")
    (root / "gamma team").mkdir()
    (root / "gamma team" / "src").mkdir()
    (root / "gamma team" / "src" / "run.py").write_text("def go(): pass\n", encoding="utf-8")
    (root / "gamma team" / "usar.toml").write_text(
        '[mission]\ntarget = "src/run.py:go"\n', encoding="utf-8"
    )
    (root / "delta").mkdir()
    (root / "delta" / "notes.txt").write_text("forgot it\n", encoding="utf-8")
    (root / "ros").mkdir()
    (root / "ros" / "pkg").mkdir()
    (root / "ros" / "pkg" / "package.xml").write_text("<package/>\n", encoding="utf-8")
    (root / "_skipped").mkdir()
    (root / ".hidden.py").write_text("", encoding="utf-8")
    (root / "readme.md").write_text("", encoding="utf-8")
    return root


def test_a_catkin_package_is_a_ros1_team(tmp_path: Path) -> None:
    root = _subs(tmp_path / "subs")
    subs = {s.team: s for s in p.discover(root)}
    assert subs["ros"].target == "ros1:" + str(root / "ros")
    assert subs["delta"].problem_outcome == "no_mission"
    assert all(len(s.sha256) == 64 for s in subs.values())


@pytest.mark.parametrize(
    ("config", "why"),
    [
        ("[mission\n", "usar.toml: not valid TOML"),
        ("[other]\n", 'usar.toml has no [mission] target = "FILE.py[:function]"'),
        ('[mission]\ntarget = "../x.py"\n', "target '../x.py' is outside the team's folder"),
        ('[mission]\ntarget = "nope.py"\n', "target 'nope.py': no such .py file"),
    ],
)
def test_a_bad_usar_toml_is_the_teams_problem(tmp_path: Path, config: str, why: str) -> None:
    (tmp_path / "subs" / "team").mkdir(parents=True)
    (tmp_path / "subs" / "team" / "usar.toml").write_text(config, encoding="utf-8")
    [sub] = p.discover(tmp_path / "subs")
    assert why in sub.problem and sub.target == ""


def _package(folder: Path, name: str) -> Path:
    (folder / "launch").mkdir(parents=True)
    (folder / "package.xml").write_text(
        f'<?xml version="1.0"?>\n<package format="2"><name>{name}</name></package>\n',
        encoding="utf-8",
    )
    (folder / "CMakeLists.txt").write_text(f"project({name})\n", encoding="utf-8")
    (folder / "launch" / "go.launch").write_text("<launch/>\n", encoding="utf-8")
    (folder / "README.md").write_text(f"roslaunch {name} go.launch\n", encoding="utf-8")
    return folder


def test_any_file_of_a_team_is_that_teams_verdict(tmp_path: Path) -> None:
    """Issue 50, finding 3: a 5 KB usar.toml nested 5,000 deep, a launch file nested as deep,
    a 100 MB YAML, a package.xml that is not UTF-8: each that team's problem in one line, and
    the other teams are found as before (the batch grades them)."""
    root = _subs(tmp_path / "subs")
    (root / "toml_bomb").mkdir()
    (root / "toml_bomb" / "usar.toml").write_text(
        "a = " + "[" * 2500 + "]" * 2500 + "\n", encoding="utf-8"
    )
    (root / "toml_bomb" / "mission.py").write_text("def main(): pass\n", encoding="utf-8")
    launch = _package(root / "launch_bomb", "lb") / "launch" / "go.launch"
    launch.write_text("<launch>" + "<group>" * 5000 + "</group>" * 5000 + "</launch>")
    big = _package(root / "big_yaml", "by") / "param.yaml"
    with big.open("wb") as f:
        f.truncate(100 * 1024 * 1024)
    (_package(root / "latin", "la") / "package.xml").write_bytes(
        b"<package><name>la</name><description>caf\xe9</description></package>"
    )
    subs = {s.team: s for s in p.discover(root)}
    assert 4900 < (root / "toml_bomb" / "usar.toml").stat().st_size < 5100
    said = {t: subs[t].problem for t in ("toml_bomb", "launch_bomb", "big_yaml", "latin")}
    assert said == {
        "toml_bomb": "usar.toml: nested deeper than 64 levels",
        "launch_bomb": "launch/go.launch: elements nested deeper than 64 levels",
        "big_yaml": "param.yaml: 104857600 bytes; usar reads at most 2097152 of this file",
        "latin": "package.xml: not UTF-8 text (byte 0xe9 at offset 40); save it as UTF-8",
    }
    assert all(subs[t].target == "" for t in said)
    assert subs["alpha"].target and subs["beta"].target and subs["gamma_team"].target


def test_an_unreadable_folder_is_a_bad_submission_and_names_must_differ(tmp_path: Path) -> None:
    root = tmp_path / "subs"
    (root / "team").mkdir(parents=True)
    os.mkfifo(root / "team" / "pipe")
    [sub] = p.discover(root)
    assert sub.problem_outcome == "bad_submission"
    assert sub.problem.startswith("unusable submission: pipe: not a regular file")
    (root / "team!").mkdir()
    with pytest.raises(UsageError, match="'team' and 'team!' are both team 'team'; rename one"):
        p.discover(root)
    with pytest.raises(UsageError, match="no submissions"):
        p.discover(_empty(tmp_path / "none"))
    with pytest.raises(UsageError, match="not a directory"):
        p.discover(root / "team" / "pipe")


def test_a_team_that_is_a_link_is_a_bad_submission_never_read(tmp_path: Path) -> None:
    """A link in the submissions folder (to a folder or a ``.py`` file) could lead anywhere on
    the machine: that team's ``bad_submission``, in the words ``usar code`` uses."""
    elsewhere = tmp_path / "elsewhere"
    (elsewhere / "team").mkdir(parents=True)
    (elsewhere / "team" / "mission.py").write_text("def main(): pass\n", encoding="utf-8")
    root = tmp_path / "subs"
    root.mkdir()
    (root / "linked").symlink_to(elsewhere / "team")
    (root / "solo.py").symlink_to(elsewhere / "team" / "mission.py")
    (root / "dangling").symlink_to(tmp_path / "nothing")  # neither a folder nor a .py: skipped
    subs = {s.team: s for s in p.discover(root)}
    assert sorted(subs) == ["linked", "solo"]
    for team, name in (("linked", "linked"), ("solo", "solo.py")):
        sub = subs[team]
        assert (sub.problem_outcome, sub.target, sub.sha256) == ("bad_submission", "", "")
        assert sub.problem == f"unusable submission: {linked([name])}"
        assert sub.path == root.resolve() / name  # the link itself, never where it leads
    assert "linked is a link: usar reads only real folders" in subs["linked"].problem


def test_a_committed_catkin_workspace_is_read_without_catkins_link(tmp_path: Path) -> None:
    """``catkin_make`` links ``src/CMakeLists.txt`` to catkin's ``toplevel.cmake``: catkin's
    link, left out (the team is graded on the rest); any other link out keeps refusing it."""
    from tests.class_folder import package

    root = tmp_path / "subs"
    team = root / "ws_team"
    package(team / "catkin_ws" / "src" / "rescue", "rescue", {"go.py": "pass\n"}, {})
    top = team / "catkin_ws" / "src" / "CMakeLists.txt"
    top.symlink_to("/opt/ros/noetic/share/catkin/cmake/toplevel.cmake")
    [sub] = p.discover(root)
    assert sub.problem_outcome != "bad_submission" and len(sub.sha256) == 64
    assert sub.target == "ros1:" + str(team)
    top.unlink()
    top.symlink_to("/etc/hostname")  # not catkin's: the present verdict
    [sub] = p.discover(root)
    assert sub.problem_outcome == "bad_submission"
    assert "catkin_ws/src/CMakeLists.txt: a link leaving the team's folder" in sub.problem


def _empty(path: Path) -> Path:
    path.mkdir()
    return path


def test_team_names() -> None:
    assert p.team_name("Team A/B") == "Team_A_B"
    assert p.team_name("..") == "team"


def test_worlds_are_seeds_then_files_with_distinct_names(tmp_path: Path) -> None:
    from usar_replay.world.scenario import course_world
    from usar_replay.world.scenario_toml import save

    [course] = p.make_worlds([], [])
    assert course.name == "course" and course.source == "the course world"
    save(course_world(), tmp_path / "seed1.toml")
    worlds = p.make_worlds([1, 2], [])
    assert [w.name for w in worlds] == ["seed1", "seed2"]
    assert worlds[0].sha256 != worlds[1].sha256
    with pytest.raises(UsageError, match="two worlds are named 'seed1'"):
        p.make_worlds([1], [str(tmp_path / "seed1.toml")])


def _plan(subs: list[p.Submission], worlds: list[p.World], out: Path) -> p.Plan:
    return p.make_plan(
        subs, worlds, out, settings_toml="", thresholds_toml="[t]\n", submissions_root=out.parent
    )


def test_a_resume_runs_again_only_what_is_not_finished(tmp_path: Path) -> None:
    root = _subs(tmp_path / "subs")
    subs = [s for s in p.discover(root) if s.team in ("alpha", "beta", "delta")]
    worlds = p.make_worlds([1], [])
    out = tmp_path / "out"
    first = _plan(subs, worlds, out)
    assert first.total == 3 and len(first.jobs) == 2 and not first.finished
    [invalid] = first.invalid
    assert (invalid.team, invalid.outcome, invalid.points) == ("delta", "no_mission", 0.0)
    alpha, beta = first.jobs
    assert p.RunJob.from_json(alpha.to_json()) == alpha
    assert alpha.inputs["mission_target"] == "alpha.py"
    # alpha finished and graded; beta recorded but its grade is for another log
    for job, grade_sha in ((alpha, "abc"), (beta, "old")):
        job.path(".mcap").parent.mkdir(parents=True, exist_ok=True)
        job.path(".mcap").write_bytes(b"log bytes")
        record = {
            "format": p.RUN_FORMAT,
            "inputs_key": job.inputs_key,
            "log_bytes": 9,
            "log_sha256": "abc",
            "wall_s": 12.5,
        }
        job.path(".run.json").write_text(json.dumps(record), encoding="utf-8")
        grade = {
            "format": p.GRADE_FORMAT,
            "log_sha256": grade_sha,
            "outcome": "done",
            "thresholds_sha256": job.thresholds_sha256,
            "points": 55,
            "max_points": 60,
        }
        job.path(".grade.json").write_text(json.dumps(grade), encoding="utf-8")
    again = _plan(subs, worlds, out)
    assert [(r.team, r.state, r.points, r.wall_s) for r in again.finished] == [
        ("alpha", "finished", 55.0, 12.5)
    ]
    assert [(j.team, j.grade_only) for j in again.jobs] == [("beta", True)]
    # a log of another size, or other inputs: recorded again
    alpha.path(".mcap").write_bytes(b"cut")
    changed = replace(subs[1], sha256="0" * 64)
    later = _plan([subs[0], changed], worlds, out)
    assert [(j.team, j.grade_only) for j in later.jobs] == [("alpha", False), ("beta", False)]


def test_read_json_takes_only_a_plain_file_holding_an_object(tmp_path: Path) -> None:
    good = tmp_path / "g.json"
    good.write_text('{"a": 1}', encoding="utf-8")
    assert p.read_json(good) == {"a": 1}
    (tmp_path / "link.json").symlink_to(good)
    assert p.read_json(tmp_path / "link.json") is None
    (tmp_path / "list.json").write_text("[1]", encoding="utf-8")
    assert p.read_json(tmp_path / "list.json") is None
    (tmp_path / "cut.json").write_text('{"a": ', encoding="utf-8")
    assert p.read_json(tmp_path / "cut.json") is None
    os.mkfifo(tmp_path / "fifo.json")
    assert p.read_json(tmp_path / "fifo.json") is None
    assert p.read_json(tmp_path / "missing.json") is None


def test_discover_submissions(tmp_path: Path) -> None:
    subs = tmp_path / "subs"
    (subs / "a_team").mkdir(parents=True)
    (subs / "a_team" / "mission.py").write_text("def main(): pass\n")
    (subs / "b team").mkdir()
    (subs / "b team" / "usar.toml").write_text('[mission]\ntarget = "src/run.py:make"\n')
    (subs / "b team" / "src").mkdir()
    (subs / "b team" / "src" / "run.py").write_text("def make(): pass\n")
    (subs / "c.py").write_text("def main(): pass\n")
    (subs / "d").mkdir()
    (subs / "e").mkdir()
    (subs / "e" / "usar.toml").write_text('[mission]\ntarget = "../c.py"\n')
    (subs / ".hidden").mkdir()
    (subs / "__pycache__").mkdir()
    (subs / "notes.txt").write_text("x")
    found = {s.team: s for s in p.discover(subs)}
    assert sorted(found) == ["a_team", "b_team", "c", "d", "e"]
    assert found["a_team"].target == str((subs / "a_team" / "mission.py").resolve())
    assert found["b_team"].target == str((subs / "b team" / "src" / "run.py").resolve()) + ":make"
    assert found["c"].target.endswith("c.py") and not found["c"].problem
    assert "no mission.py" in found["d"].problem and not found["d"].target
    assert "outside the team's folder" in found["e"].problem
    (subs / "c").mkdir()
    (subs / "c" / "mission.py").write_text("")
    with pytest.raises(UsageError, match="both team 'c'"):
        p.discover(subs)


def test_parse_seeds() -> None:
    assert p.parse_seeds("0-4") == [0, 1, 2, 3, 4]
    assert p.parse_seeds("7,0-1,1") == [0, 1, 7]
    for bad in ("", "a", "4-0", "1-"):
        with pytest.raises(UsageError):
            p.parse_seeds(bad)
    with pytest.raises(UsageError, match="expected N, N-M or a comma list"):
        p.parse_seeds("a")
    with pytest.raises(UsageError, match="0-20000 is not a range from low to high"):
        p.parse_seeds("0-20000")


def _ros_team(root: Path, name: str, readme: str) -> Path:
    team = root / name
    (team / "launch").mkdir(parents=True)
    (team / "package.xml").write_text(
        "<package><name>final_project</name></package>\n", encoding="utf-8"
    )
    (team / "CMakeLists.txt").write_text(
        "project(final_project)\nadd_executable(a a.cpp)\nadd_executable(b b.cpp)\n",
        encoding="utf-8",
    )
    (team / "README.md").write_text(readme, encoding="utf-8")
    return team


def test_the_instructors_starts_are_labelled_theirs_and_rerun_the_team(tmp_path: Path) -> None:
    """issue 50: the team's usar.toml is the team's word; the instructor's starts file (not in
    any team's folder) is the instructor's, and changing it redoes that team's runs only."""
    from usar_replay.ros1.starts_file import InstructorStart

    root = tmp_path / "subs"
    _ros_team(root, "own", "run `rosrun final_project a`\n")
    (root / "own" / "usar.toml").write_text('[ros1]\nnode = "b"\n', encoding="utf-8")
    _ros_team(root, "told", "rosrun final_project a\n")
    told = InstructorStart(node="b", note="office hours", label="the instructor's s.toml [told]")
    subs = {s.team: s for s in p.discover(root, {"told": told})}
    assert (subs["own"].start, subs["own"].start_source) == (
        "rosrun final_project b",
        "the team's usar.toml [ros1]",
    )
    assert (subs["told"].start, subs["told"].start_source) == (
        "rosrun final_project b",
        "the instructor's s.toml [told]: office hours",
    )
    worlds = p.make_worlds([1], [])
    jobs = {j.team: j for j in _plan(list(subs.values()), worlds, tmp_path / "out").jobs}
    assert "instructor_start" not in jobs["own"].inputs
    assert jobs["told"].instructor_start == told.to_json()
    assert p.RunJob.from_json(jobs["told"].to_json()) == jobs["told"]
    again = {s.team: s for s in p.discover(root, {"told": replace(told, node="a")})}
    rejobs = {j.team: j for j in _plan(list(again.values()), worlds, tmp_path / "out").jobs}
    assert rejobs["told"].inputs_key != jobs["told"].inputs_key
    assert rejobs["own"].inputs_key == jobs["own"].inputs_key
    with pytest.raises(UsageError, match=r"--starts: \[tlod\] is no team of"):
        p.discover(root, {"tlod": told})


def test_a_written_start_the_package_cannot_start_is_the_teams_line(tmp_path: Path) -> None:
    """issue 51: a name the package does not build, with no obvious fallback: the team's
    no_mission with the line that names it (never a crash of code that never ran)."""
    root = tmp_path / "subs"
    _ros_team(root, "t", '4. Run command "rosrun final_project final_project_nod"\n')
    [sub] = p.discover(root)
    assert (sub.target, sub.problem_outcome) == ("", "no_mission")
    assert sub.problem.startswith(
        "README.md line 1 names `final_project_nod`, which the package does not build (it has a, b)"
    )
