"""Every log is gradable (issue 31, point 5): a run that ends before its first tick.

A mission that raises at import and a ROS 1 package whose node exits 1 before the first clock
are recorded, then graded as a user does (``usar grade FILE``): the log holds the world's facts
written up front (``/tf_static``, ``/map``, ground truth at t0), so it is graded, every rubric
line fails and says why, and the exit code is the README's ``1`` (a line failed), without a
traceback of usar's. The recorder's own grade (what ``usar batch`` keeps) says the same.
"""

from __future__ import annotations

import os
import textwrap
from pathlib import Path

import pytest
from clitools import usar
from example_worlds import quick_room

from usar_replay.grading.grade import grade_file
from usar_replay.log.run import open_run
from usar_replay.pipeline.record import record
from usar_replay.world.scenario_toml import save

UP_FRONT = ("/tf_static", "/map", "/ground_truth/explorer/pose", "/ground_truth/markers")


def _graded_as_never_ran(log: Path, outcome: str, *needles: str) -> None:
    """``usar grade`` grades ``log``: exit 1, every line failed with the reason."""
    run = open_run(log)
    assert run.outcome == outcome, run.outcome_reason
    assert set(UP_FRONT) <= set(run.topics), sorted(run.topics)
    done = usar("grade", str(log))
    assert done.returncode == 1, done.stdout + done.stderr
    assert "Traceback" not in done.stderr and "usar: error" not in done.stderr
    report = grade_file(log)
    assert report.checks and not any(c.passed for c in report.checks)
    assert report.points == 0
    for check in report.checks:
        assert check.measured.startswith(f"the mission {outcome}"), check.measured
        for needle in needles:
            assert needle in check.measured, check.measured
    assert "before its first tick" in " ".join(done.stdout.split())  # the table wraps


def test_a_mission_that_raises_at_import_leaves_a_gradable_log(tmp_path: Path) -> None:
    mission = tmp_path / "broken.py"
    mission.write_text('raise RuntimeError("no config here")\n', encoding="utf-8")
    out = tmp_path / "broken.mcap"
    result = record(quick_room(), out, mission=str(mission))
    assert result.outcome == "crashed"
    _graded_as_never_ran(out, "crashed", "RuntimeError: no config here")
    # the recorder's grade (kept by `usar batch`) is the file's grade
    assert result.grade is not None
    live = result.grade.report(out)
    assert [(c.id, c.passed, c.measured) for c in live.checks] == [
        (c.id, c.passed, c.measured) for c in grade_file(out).checks
    ]


def test_a_run_that_ticked_is_graded_as_it_went(tmp_path: Path) -> None:
    """The rule is only for a run that never ticked: a crash later keeps the lines' own
    measures (what the world showed up to the crash)."""
    mission = tmp_path / "later.py"
    mission.write_text(
        textwrap.dedent(
            """
            from usar_replay.api import Node

            def main():
                node = Node("late")
                node.create_timer(0.5, lambda: 1 / 0)
            """
        ),
        encoding="utf-8",
    )
    out = tmp_path / "later.mcap"
    result = record(quick_room(), out, mission=str(mission))
    assert result.outcome == "crashed", result.outcome_reason
    assert result.sim_duration_s > 0
    assert not any("before its first tick" in c.measured for c in grade_file(out).checks)


_PACKAGE_XML = """<?xml version="1.0"?>
<package format="2">
  <name>gives_up</name>
  <version>0.0.1</version>
  <description>a node that exits 1 before the first clock</description>
  <maintainer email="team@example.com">team</maintainer>
  <license>MIT</license>
  <buildtool_depend>catkin</buildtool_depend>
  <depend>roscpp</depend>
</package>
"""
_CMAKE = """cmake_minimum_required(VERSION 3.0.2)
project(gives_up)
find_package(catkin REQUIRED COMPONENTS roscpp)
catkin_package()
include_directories(${catkin_INCLUDE_DIRS})
add_executable(gives_up_node src/gives_up_node.cpp)
target_link_libraries(gives_up_node ${catkin_LIBRARIES})
"""
_NODE = """#include <ros/ros.h>
#include <cstdio>
int main(int argc, char** argv) {
  ros::init(argc, argv, "gives_up_node");
  std::fprintf(stderr, "no map configured, giving up\\n");
  return 1;
}
"""


def _write_package(root: Path) -> Path:
    (root / "src").mkdir(parents=True)
    (root / "package.xml").write_text(_PACKAGE_XML, encoding="utf-8")
    (root / "CMakeLists.txt").write_text(_CMAKE, encoding="utf-8")
    (root / "src" / "gives_up_node.cpp").write_text(_NODE, encoding="utf-8")
    return root


def test_a_ros1_node_that_exits_before_the_first_clock_leaves_a_gradable_log(
    tmp_path: Path,
) -> None:
    if not Path("/usr/bin/roslaunch").exists():
        pytest.skip("ROS 1 (Debian's ros-base) is not installed")
    pkg = _write_package(tmp_path / "gives_up")
    world = tmp_path / "room.toml"
    save(quick_room(), world)
    out = tmp_path / "gives_up.mcap"
    env = {**os.environ, "XDG_CACHE_HOME": str(tmp_path / "cache")}
    done = usar(
        "record", "--quiet", "--scenario", str(world), "--ros1", str(pkg),
        "--node", "gives_up_node", "--out", str(out), env=env,
    )  # fmt: skip
    assert done.returncode == 4, done.stdout + done.stderr
    _graded_as_never_ran(out, "crashed", "giving up")
