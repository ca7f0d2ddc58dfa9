"""A class folder graded end to end (issue 42): each team started as its instructions say, a
team's problem its own verdict, the class on one page.

The teams (:mod:`class_folder`) are the real class's shapes, as small Python-node packages: the
template's twelve launch files with ``doc/instructions.txt`` naming the world and the node, a
README naming a launch file and a ``rosservice call``, one node and no instructions, two nodes
and no instructions, a team's own ``usar.toml`` over its wrong README (started as the instructor's
starts file says in the batch: ``--starts``, issue 50). Real catkin_make,
roslaunch, rosservice and the bridge, in the kernel sandbox, on the one-room world.
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import pytest
from class_folder import make_class, make_pair
from conftest import one_room

from usar_replay.batch.plan import discover
from usar_replay.cli.main import main
from usar_replay.grading.grade import grade_file
from usar_replay.grading.reports import to_table
from usar_replay.log import ros1_run
from usar_replay.log.info import describe
from usar_replay.log.rosout import LogRequest, lines
from usar_replay.log.run import open_run
from usar_replay.world.scenario_toml import save


@pytest.fixture(autouse=True, scope="module")
def _build_cache(module_build_cache: Path) -> None:
    """One build cache for this module: usar's underlay is built once."""


@pytest.fixture(scope="module")
def subs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return make_class(tmp_path_factory.mktemp("class") / "subs")


def test_the_plan_reads_each_teams_start(subs: Path) -> None:
    teams = {s.team: s for s in discover(subs)}
    assert teams["template"].start == (
        "roslaunch final_project multiple_robots.launch; rosrun final_project explorer.py"
    )
    assert teams["template"].start_source == "doc/instructions.txt lines 3, 5"
    assert teams["readme_service"].start == (
        "roslaunch rescue go.launch; rosservice call /start 'data: true'"
    )
    assert teams["readme_service"].start_source == "README.md line 4"
    assert (teams["one_node"].start, teams["one_node"].start_source) == (
        "rosrun solo solo.py",
        "the package's only executable",
    )
    duo = teams["two_nodes"]
    assert duo.problem_outcome == "no_mission" and duo.target == ""
    assert "explorer_node.py, follower_node.py" in duo.problem
    assert (teams["override"].start, teams["override"].start_source) == (
        "rosrun chosen right.py",
        "the team's usar.toml [ros1]",
    )


def test_a_class_folder_grades_end_to_end(
    subs: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    world = tmp_path / "room.toml"
    save(one_room(), world)
    out = tmp_path / "out"
    args = ["batch", str(subs), "-o", str(out), "--scenario", str(world), "--jobs", "2"]
    starts = tmp_path / "starts.toml"  # the instructor's word, outside every team's folder
    starts.write_text('[override]\nnode = "right.py"\nnote = "README names wrong.py"\n')
    args += ["--starts", str(starts)]
    code = main([*args, "--max-sim-time", "3", "--gradescope", "--quiet"])
    said = capsys.readouterr()
    assert code == 0, said.out + said.err  # every run has a grade: no error of usar's
    assert "error" not in said.err.lower(), said.err
    grades = {
        team: json.loads((out / team / "room.grade.json").read_text())
        for team in ("template", "readme_service", "one_node", "override")
    }
    for team, grade in grades.items():  # each ran to the batch's sim time: graded, not errors
        assert grade["outcome"] == "max_sim_time", (team, grade["outcome_reason"])
        assert grade["max_points"] == 60 and grade["start"] and grade["start_source"], team
    assert grades["template"]["start"] == (
        "roslaunch final_project multiple_robots.launch; rosrun final_project explorer.py"
    )
    assert grades["override"]["start"] == "rosrun chosen right.py"
    assert grades["override"]["start_source"] == (
        "the instructor's starts.toml [override]: README names wrong.py"
    )
    # the two commands ran together: the world's parameter loaded, its detector dropped, and the
    # team's node ran; the third command reached the service's callback
    template = open_run(out / "template" / "room.mcap")
    ros1 = ros1_run.of(template)
    assert ros1 is not None
    assert (ros1.launch, ros1.node) == ("multiple_robots.launch", "explorer.py")
    assert [n.name for n in ros1.nodes] == ["/explorer"]
    assert [n.package for n in ros1.replaced] == ["aruco_detect"]
    info = describe(template)
    assert "Start read from" in info and "instructions.txt lines 3, 5" in info
    report = grade_file(out / "template" / "room.mcap")
    assert report.started_with.endswith("rosrun final_project explorer.py (doc/instructions.txt "
                                        "lines 3, 5)")
    assert "Started with: roslaunch final_project" in to_table(report, 100)
    said_log = "\n".join(lines(open_run(out / "readme_service" / "room.mcap"), LogRequest()))
    assert "started by /start: True" in said_log, said_log
    right = "\n".join(lines(open_run(out / "override" / "room.mcap"), LogRequest()))
    assert "right up" in right and "wrong" not in right
    # the class: the problem and the starts in every summary, and the page
    table = (out / "summary.txt").read_text()
    assert "two_nodes: no_mission: package duo: no roslaunch/rosrun line" in table
    assert "readme_service: roslaunch rescue go.launch; rosservice call /start" in table
    rows = {r["team"]: r for r in csv.DictReader(io.StringIO((out / "summary.csv").read_text()))}
    assert "explorer_node.py, follower_node.py" in rows["two_nodes"]["problems"]
    assert rows["two_nodes"]["total"] == "0"
    assert rows["one_node"]["start_from"] == "the package's only executable"
    duo = json.loads((out / "two_nodes" / "results.json").read_text())
    assert duo["score"] == 0 and "follower_node.py" in duo["output"]
    solo = json.loads((out / "one_node" / "results.json").read_text())
    assert "Started with: rosrun solo solo.py (the package's only executable)" in solo["output"]
    page = (out / "class.html").read_text()
    assert page.count("<tr>") == 1 + 5 and "no_mission" in page
    # usar report of the batch folder: each run's page, and the class page linking them
    pages = tmp_path / "pages"
    assert main(["report", str(out), "-o", str(pages)]) in (0, 1)
    linked = (pages / "class.html").read_text()
    assert "href='room.html'" in linked or "href='room-2.html'" in linked


def test_engines_agree_for_a_ros1_team(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A two-node team whose launch ends with roslaunch's SIGINT to the other node: the same
    verdict and the same log bytes from the local engine and from a Ray worker (which blocks
    SIGINT and runs at nice 15: the run's process takes a state of its own, whatever its
    parent's; usar_replay/batch/run_state.py)."""
    ray = pytest.importorskip("ray", reason="Ray is not installed (pip install 'usar-replay[ray]')")
    subs = make_pair(tmp_path / "subs")
    world = tmp_path / "room.toml"
    save(one_room(), world)
    args = ["batch", str(subs), "--scenario", str(world), "--jobs", "1", "--quiet"]
    args += ["--max-sim-time", "6"]
    assert main([*args, "-o", str(tmp_path / "local")]) == 0, capsys.readouterr().err
    ray.init(num_cpus=1, include_dashboard=False, log_to_driver=False)
    try:
        assert main([*args, "-o", str(tmp_path / "ray"), "--engine", "ray"]) == 0
    finally:
        ray.shutdown()
    local, remote = (
        json.loads((tmp_path / d / "pair" / "room.grade.json").read_text())
        for d in ("local", "ray")
    )
    assert local["outcome"] == "done" or local["outcome"] == "max_sim_time", local
    assert (remote["outcome"], remote["outcome_reason"]) == (
        local["outcome"],
        local["outcome_reason"],
    )
    assert remote["log_sha256"] == local["log_sha256"]
