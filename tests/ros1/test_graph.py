"""ros1/graph: the student's processes as the bridge starts and reads them: a real ``rosrun``
of a toy package (a shell script node, found through ``ROS_PACKAGE_PATH`` as the workspace's
``setup.bash`` sets it), its exit code, its own output file, and roslaunch's report of a death
in the graph's log. (roslaunch itself: tests/ros1/test_record.py, tests/e2e/test_ros1.py.)"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from proctools import wait_for

from usar_replay.ros1.building.workspace import catkin_env
from usar_replay.ros1.graph import Graph, tail

PACKAGE_XML = """<?xml version="1.0"?>
<package format="2"><name>toy</name><version>0.0.1</version><description>toy</description>
<maintainer email="toy@example.com">toy</maintainer><license>MIT</license>
<buildtool_depend>catkin</buildtool_depend></package>
"""


def _graph(tmp_path: Path, script: str) -> Graph:
    if shutil.which("rosrun") is None:
        pytest.skip("ROS 1's rosrun is not installed")
    ws, run = tmp_path / "ws", tmp_path / "run"
    pkg = ws / "src" / "toy"
    pkg.mkdir(parents=True)
    (ws / "devel").mkdir()
    run.mkdir()
    (pkg / "package.xml").write_text(PACKAGE_XML)
    node = pkg / "toy_node"
    node.write_text("#!/bin/sh\n" + script)
    node.chmod(0o755)
    (ws / "devel" / "setup.bash").write_text(f'export ROS_PACKAGE_PATH="{ws / "src"}"\n')
    config = {"workspace": str(ws), "run_dir": str(run), "package": "toy", "node": "toy_node"}
    return Graph(config, catkin_env())


def test_a_node_that_fails_gives_its_exit_code_and_its_last_lines(tmp_path: Path) -> None:
    graph = _graph(tmp_path, "echo starting\necho 'no map' >&2\nexit 3\n")
    assert graph.what == "rosrun toy toy_node"
    wait_for(lambda: graph.exit_status() is not None, "the node's end")
    assert graph.exit_status() == (3, "")
    # stdout and stderr, in its own file, shown with the node's name
    assert graph.tail() == "[toy_node] starting\n[toy_node] no map\n"
    assert not graph.launcher_stopping()
    graph.stop()  # nothing left to stop: no error


def test_roslaunchs_report_of_a_death_is_the_problem(tmp_path: Path) -> None:
    graph = _graph(tmp_path, "exit 0\n")
    wait_for(lambda: graph.exit_status() is not None, "the node's end")
    assert graph.exit_status() == (0, "")
    # roslaunch exits 0 when a node died: its line in the graph's log says how
    with graph.log_path.open("a") as log:
        log.write("[explorer-2] process has died [pid 41, exit code -11, cmd explorer].\n")
        log.write("[explorer-2] process has finished cleanly\nInitiating shutdown!\n")
    code, problem = graph.exit_status() or (None, "")
    assert code == 0
    assert problem.startswith("[explorer-2] process has died [pid 41, exit code -11")
    assert graph.launcher_stopping()
    assert tail(graph.log_path, 1) == "Initiating shutdown!"
    assert tail(tmp_path / "absent.log") == ""


def test_third_commands_run_as_argv_never_through_a_shell(tmp_path: Path) -> None:
    graph = _graph(tmp_path, "trap 'exit 0' INT\nwhile :; do sleep 0.1; done\n")
    pwned = tmp_path / "pwned"
    try:
        graph.run_after_launch(
            [
                f"echo hi > {pwned}",  # not a third command: refused, on record
                f"rostopic pub -h $(touch {pwned}) '; touch {pwned}'",  # words, not shell text
            ]
        )
        assert len(graph.after) == 1
        graph.after[0].wait(timeout=60)
    finally:
        graph.stop()
    out = graph.output_dir
    refused = (out / "after_launch_1.out").read_text()
    assert refused == f"usar: refused: not a rosservice call or rostopic pub: echo hi > {pwned}\n"
    assert "Usage: rostopic pub" in (out / "after_launch_2.out").read_text()
    assert not pwned.exists()
