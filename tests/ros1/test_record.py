"""What a ROS 1 run keeps: the package's own topics, its stored markers, each node's lines.

A two-node package (``examples/ros1/usar_two_nodes``: the explorer node publishes its stored
markers latched as a ``geometry_msgs/PoseArray`` on ``/explorer/marker_poses`` and a
``std_msgs/Int32`` count usar has no type for, then calls the follower's ``std_srvs/Trigger``
service; the follower node waits for both) is built and
recorded on the one-room world, once for the module; then the log is read as a student would:
``usar echo``, ``usar log --node``, ``usar log --output`` (each node's stdout and stderr),
``usar info`` (the package, its nodes, the build), the summary, the report's picture and the
viewer's scene. The run's private files are read as untrusted (no symlink followed, bounded).
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterator
from pathlib import Path

import pytest
from clitools import usar
from example_worlds import quick_room

from usar_replay.core import msgs
from usar_replay.grading.htmlreport import collect
from usar_replay.log.run import open_run
from usar_replay.ros1.building.workspace import find_package, package_sha256
from usar_replay.viewer.scene import Scene
from usar_replay.world.scenario_toml import save

PACKAGE = Path(__file__).resolve().parents[2] / "examples" / "ros1" / "usar_two_nodes"


@pytest.fixture(scope="module")
def recorded(
    tmp_path_factory: pytest.TempPathFactory, module_build_cache: Path
) -> Iterator[tuple[Path, str]]:
    """The two-node package recorded on the quick one-room world: (log, what `usar record`
    printed)."""
    tmp = tmp_path_factory.mktemp("two_nodes")
    world = tmp / "room.toml"
    save(quick_room(), world)
    out = tmp / "two.mcap"
    done = usar("record", "--scenario", str(world), "--ros1", str(PACKAGE), "--out", str(out))
    assert done.returncode == 0, done.stdout + done.stderr
    yield out, done.stdout + done.stderr


def test_the_package_topics_are_in_the_log(recorded: tuple[Path, str]) -> None:
    out, _ = recorded
    run = open_run(out)
    assert run.outcome == "done", run.outcome_reason
    topics = run.topics
    assert topics["/explorer/marker_poses"].msgtype == "geometry_msgs/msg/PoseArray"
    # a type usar has no value for stays in its ROS 1 encoding, with its definition
    assert topics["/explorer/stored_count"].msgtype == "std_msgs/Int32"
    assert run.reader.ros1_definition("/explorer/stored_count") == (
        "std_msgs/Int32",
        "int32 data\n",
    )
    poses = [m.msg for m in run.messages(["/explorer/marker_poses"])]
    assert len(poses) == 1 and isinstance(poses[0], msgs.PoseArray)
    assert len(poses[0].poses) == 1
    # usar's own topics are not recorded twice (the bridge's move_base action topics)
    assert not [t for t in topics if "/move_base/" in t]


def test_echo_reads_both_encodings(recorded: tuple[Path, str]) -> None:
    out, _ = recorded
    poses = usar("echo", str(out), "/explorer/marker_poses")
    assert poses.returncode == 0, poses.stderr
    assert "poses:\n- position:\n    x: 1.9" in poses.stdout
    count = usar("echo", str(out), "explorer/stored_count")
    assert count.returncode == 0, count.stderr
    assert count.stdout.splitlines()[1:] == ["data: 1", "---"]


def test_the_stored_markers_are_shown(recorded: tuple[Path, str]) -> None:
    out, printed = recorded
    assert "stored on /explorer/marker_poses at (1.99" in printed
    pic = collect(open_run(out))
    assert list(pic.stored) == [0] and pic.stored_on == "/explorer/marker_poses"


def test_log_by_node_finds_each_node(recorded: tuple[Path, str]) -> None:
    out, _ = recorded
    for name in ("explorer", "/explorer"):
        got = usar("log", str(out), "--node", name)
        assert got.returncode == 0, got.stderr
        assert "[explorer]: explorer: home" in got.stdout
        assert "[follower]" not in got.stdout
    follower = usar("log", str(out), "--node", "follower").stdout
    assert "waiting for the explorer's markers" in follower


def test_the_nodes_talk_through_a_std_srvs_service(recorded: tuple[Path, str]) -> None:
    """The explorer calls the follower's ``/follower/go`` (std_srvs/Trigger) once it is home,
    as many groups wrote it: the call is answered in the run, and the follower goes only then
    (the run scores as a whole, so its markers were visited after the call)."""
    out, _ = recorded
    got = usar("log", str(out), "--node", "explorer").stdout
    assert "[explorer]: explorer: the go call answered: going" in got
    assert "the go call failed" not in got
    graded = usar("grade", str(out))
    assert graded.returncode == 0, graded.stdout + graded.stderr


def test_info_names_the_package_its_nodes_and_the_build(recorded: tuple[Path, str]) -> None:
    out, _ = recorded
    got = usar("info", str(out))
    assert got.returncode == 0, got.stderr
    text = got.stdout
    assert f"ROS 1 package: usar_two_nodes ({PACKAGE})" in text
    assert f"sha256:        {package_sha256(find_package(PACKAGE))}" in text
    assert "Started with:  roslaunch usar_two_nodes usar_two_nodes.launch" in text
    nodes = "/explorer (usar_two_nodes/explorer_node), /follower (usar_two_nodes/follower_node)"
    assert f"Nodes:         {nodes}" in text
    # the build's wall time (and whether it was cached) is not the log's: the same run, the
    # same bytes, on a machine that built the package just now or before (issue 42)
    assert not re.search(r"^Build:", text, re.M), text
    # settings: only those usar applied (not the Python mission's own, such as settle_frames)
    settings = text.split("Settings (those that applied to the ROS 1 run):\n")[1]
    settings = settings.split("Parameters the package's nodes read:\n")[0]
    assert "  record.control_hz = 20 Hz" in settings
    # move_base's tolerances: the template's (no move_base launch), not a setting nobody gave
    assert "mission.xy_tolerance" not in settings
    assert (
        "move_base:     follower: goal tolerances xy 0.05 m, yaw 0.17 rad, from the course "
        "template's default"
    ) in text
    assert "settle_frames" not in settings and "mission.spin_speed" not in settings
    # what the nodes read: usar's values, a parameter usar did not set, no ROS internals
    assert "  /mission/settle_frames = 5  (/explorer)" in text  # the explorer reads it
    assert "  /usar_two_nodes/standoff = not set by usar  (/follower)" in text
    assert "/tcp_keepalive" not in text and "/use_sim_time" not in text
    assert all(len(line) <= 100 for line in text.splitlines())


def test_log_output_shows_each_nodes_stdout_and_stderr(recorded: tuple[Path, str]) -> None:
    out, _ = recorded
    got = usar("log", str(out), "--output", "--node", "explorer")
    assert got.returncode == 0, got.stderr
    lines = got.stdout.splitlines()
    assert lines[0] == "--- /explorer: stdout and stderr ---"
    assert "explorer node: started" in lines  # printf on stdout
    assert "explorer node: a line on stderr" in lines  # fprintf on stderr
    assert any(
        line.endswith("explorer: home, 1 markers on /explorer/marker_poses") for line in lines
    )
    assert "\x1b" not in got.stdout and "follower" not in got.stdout.replace("/explorer", "")
    both = usar("log", str(out), "--output").stdout
    assert "--- /follower: stdout and stderr ---" in both
    assert "follower: mission complete" in both
    missing = usar("log", str(out), "--output", "--node", "nobody")
    assert missing.returncode == 2
    assert "no output of node /nobody kept; the nodes': /explorer, /follower" in missing.stderr


def test_view_shows_the_stored_pose_array(recorded: tuple[Path, str]) -> None:
    out, _ = recorded
    run = open_run(out)
    scene = Scene(run.scenario)
    for m in run.messages():
        scene.feed(m.topic, m.msg, m.log_time_ns)
    rows = scene.stored_markers
    assert rows.lengths == [1] and rows.labels == ["stored 0"]
    assert abs(rows.items[0][0] - 1.994) < 0.01 and abs(rows.items[0][1] - 0.401) < 0.01


@pytest.mark.slow
def test_the_log_does_not_depend_on_where_the_build_is_kept(
    recorded: tuple[Path, str], tmp_path: Path
) -> None:
    """The same package recorded again from another build-cache root, in a private build folder
    (a batch's, with a random name): the /rosout lines are the same bytes, because the build
    and the run see the workspace at the sandbox's fixed paths (docs/ros1.md), never the host's
    (a C++ node's ``file`` field is its ``__FILE__``). Slow (a second build and run, some 50 s
    of the fast suite's 15 minutes): the fast suite's
    ``tests/e2e/test_class_folder.py::test_engines_agree_for_a_ros1_team`` holds the same, two
    private build folders of two output folders giving one log sha256."""
    from usar_replay.core.settings import RunSettings
    from usar_replay.ros1.process import Ros1Options
    from usar_replay.ros1.record import record_ros1
    from usar_replay.sandbox.kernel_sandbox import bwrap_available

    if not bwrap_available()[0]:
        pytest.skip("only a sandboxed run is path-independent (no bubblewrap here)")
    first, _ = recorded
    before = os.environ.get("XDG_CACHE_HOME")
    os.environ["XDG_CACHE_HOME"] = str(tmp_path / "another" / "cache")
    out = tmp_path / "again.mcap"
    try:
        options = Ros1Options(cache=False)  # a private build folder, as a batch's team gets
        result = record_ros1(quick_room(), out, PACKAGE, RunSettings(), options=options)
    finally:
        if before is None:
            del os.environ["XDG_CACHE_HOME"]
        else:
            os.environ["XDG_CACHE_HOME"] = before
    assert result.outcome == "done", result

    def rosout(log: Path) -> list[tuple[int, bytes]]:
        return [(m.log_time_ns, m.data) for m in open_run(log).messages(["/rosout"], decode=False)]

    again = rosout(out)
    assert again == rosout(first) and len(again) >= 3
    files = {m.msg.file for m in open_run(out).messages(["/rosout"]) if isinstance(m.msg, msgs.Log)}
    cpp = sorted(f for f in files if f.endswith(".cpp"))
    assert cpp and all(f.startswith("/ros1/ws/src/usar_two_nodes/src/") for f in cpp), files
    assert not [f for f in files if "cache" in f or str(tmp_path) in f], files


def test_a_teams_file_no_parser_may_read_is_one_line_before_any_build(tmp_path: Path) -> None:
    """Issue 50, finding 3, for ``usar record --ros1``: a usar.toml nested 5,000 deep beside a
    package is ``usar: error:`` and one line (exit 2), before anything is built."""
    from catkintools import package as catkin_package

    team = tmp_path / "team"
    catkin_package(team / "pkg", "deep_team")
    (team / "usar.toml").write_text("a = " + "[" * 5000 + "]" * 5000 + "\n", encoding="utf-8")
    world = tmp_path / "room.toml"
    save(quick_room(), world)
    got = usar("record", "--ros1", str(team), "--scenario", str(world), "--out",
               str(tmp_path / "x.mcap"), "--max-sim-time", "1")  # fmt: skip
    assert got.returncode == 2, got.stderr
    assert got.stderr.strip() == "usar: error: usar.toml: nested deeper than 64 levels"
    assert not (tmp_path / "x.mcap").exists()
