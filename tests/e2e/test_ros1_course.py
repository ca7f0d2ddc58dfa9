"""A copy of the course's ``final_project`` template, built and run as on a course machine.

``examples/ros1/course_template`` is that shape (issue 31): its ``find_package`` lists tf,
tf2_geometry_msgs, std_srvs, image_transport, cv_bridge and gazebo_ros beside what the node
uses; the course's ``multiple_robots.launch`` includes gazebo_ros's ``empty_world.launch``,
spawns the robots, sets ``robot_description`` through xacro, starts amcl, move_base,
map_server, aruco_detect, robot_state_publisher and rviz; ``param/aruco_lookup.yaml`` holds
four wrong targets; the team's ``team.launch`` includes it and starts the team's node. Built
with Debian's packages and usar's stand-ins, run with real catkin_make and roslaunch, recorded
to a graded end on the one-room world: the course's servers are not started (``usar info``
lists them as replaced), the team's parameters load, and the world's one target wins.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from conftest import one_room

from usar_replay.cli.main import main
from usar_replay.grading.grade import grade_file
from usar_replay.log import ros1_run
from usar_replay.log.info import describe
from usar_replay.log.run import open_run
from usar_replay.ros1.building import debian
from usar_replay.world.scenario_toml import save

TEMPLATE = Path(__file__).resolve().parents[2] / "examples" / "ros1" / "course_template"


@pytest.fixture(autouse=True, scope="module")
def _build_cache(module_build_cache: Path) -> None:
    """One build cache for this module: usar's underlay is built once."""


def test_debian_ros1_is_installed() -> None:
    assert debian.missing() == [], debian.install_line(debian.missing())


def test_the_course_template_runs_with_usars_stand_ins(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    world = tmp_path / "room.toml"
    save(one_room(), world)
    out = tmp_path / "team.mcap"
    args = ["record", "--ros1", str(TEMPLATE), "--launch", "team.launch", "--scenario", str(world)]
    assert main([*args, "--out", str(out), "--quiet"]) == 0, capsys.readouterr()
    run = open_run(out)
    assert run.outcome == "done", run.outcome_reason
    report = grade_file(out)
    assert report.passed and report.points == report.max_points == 60, [
        (c.id, c.measured) for c in report.checks if not c.passed
    ]
    ros1 = ros1_run.of(run)
    assert ros1 is not None
    # only the team's node ran; the course's servers were replaced, and the log says which
    assert [(n.name, n.package, n.type) for n in ros1.nodes] == [
        ("/final_project_node", "final_project", "final_project_node")
    ]
    assert list(ros1_run.node_outputs(run)) == ["/final_project_node"]
    replaced = {(n.name, n.package, n.type) for n in ros1.replaced}
    assert {
        ("/gazebo", "gazebo_ros", "gzserver"),
        ("/explorer/spawn_turtlebot", "gazebo_ros", "spawn_model"),
        ("/aruco_detect", "aruco_detect", "aruco_detect"),
        ("/map_server", "map_server", "map_server"),
        ("/explorer_amcl", "amcl", "amcl"),
        ("/follower_move_base", "move_base", "move_base"),
        ("/follower/robot_state_publisher", "robot_state_publisher", "robot_state_publisher"),
        ("/rviz", "rviz", "rviz"),
    } <= replaced
    registered = {p for read in ros1.parameters for p in read.read_by}
    assert registered == {"/final_project_node"}
    text = describe(run)
    assert "Replaced:" in text and "(gazebo_ros/gzserver)" in text
    assert all(len(line) <= 100 for line in text.splitlines())
    # the world's one target, not the team's four wrong ones; the team's own parameters load
    said = ros1_run.node_outputs(run)["/final_project_node"]
    assert "explorer: target_1 = [1.100, 0.300]" in said
    assert "explorer: 1 lookup targets" in said
    assert "team group 0: 20.0 Hz" in said  # /team/name and ~rate from param/team.yaml
    read = {p.name: p.value for p in ros1.parameters}
    assert read["/aruco_lookup_locations/target_1"] == "[1.1, 0.3]"


def _copy(tmp_path: Path, edit: str, new: str) -> Path:
    pkg = tmp_path / "final_project"
    shutil.copytree(TEMPLATE, pkg)
    cmake = pkg / "CMakeLists.txt"
    cmake.write_text(cmake.read_text(encoding="utf-8").replace(edit, new), encoding="utf-8")
    return pkg


def test_a_ros_package_debian_has_but_is_not_installed_names_its_apt_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``laser_geometry`` is Debian's liblaser-geometry-dev, not in the README's line: the
    build fails at configure time with the one line to run."""
    if Path("/usr/share/laser_geometry/package.xml").exists():
        pytest.skip("liblaser-geometry-dev is installed here")
    pkg = _copy(tmp_path, "  gazebo_ros\n", "  gazebo_ros\n  laser_geometry\n")
    world = tmp_path / "room.toml"
    save(one_room(), world)
    out = tmp_path / "b.mcap"
    args = ["record", "--ros1", str(pkg), "--launch", "team.launch", "--scenario", str(world)]
    code = main([*args, "--out", str(out)])
    text = capsys.readouterr().out
    assert code == 4, text
    hint = "hint: install laser_geometry: apt-get install -y --no-install-recommends "
    assert hint + "liblaser-geometry-dev" in text, text
    assert "check its name" not in text


def test_gazebos_api_is_refused_with_a_hint(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A Gazebo plugin: ``gazebo_ros`` resolves (usar's stand-in), Gazebo's headers do not."""
    pkg = tmp_path / "gz_plugin"
    (pkg / "src").mkdir(parents=True)
    (pkg / "package.xml").write_text(
        '<?xml version="1.0"?><package format="2"><name>gz_plugin</name><version>0.0.0</version>'
        "<description>d</description><maintainer email='a@b.org'>a</maintainer>"
        "<license>MIT</license><buildtool_depend>catkin</buildtool_depend>"
        "<depend>roscpp</depend><depend>gazebo_ros</depend></package>\n",
        encoding="utf-8",
    )
    (pkg / "CMakeLists.txt").write_text(
        "cmake_minimum_required(VERSION 3.0.2)\nproject(gz_plugin)\n"
        "find_package(catkin REQUIRED COMPONENTS roscpp gazebo_ros)\ncatkin_package()\n"
        "include_directories(${catkin_INCLUDE_DIRS})\n"
        "add_executable(plugin src/plugin.cpp)\n",
        encoding="utf-8",
    )
    (pkg / "src" / "plugin.cpp").write_text(
        "#include <gazebo/gazebo.hh>\nint main() { return 0; }\n", encoding="utf-8"
    )
    world = tmp_path / "room.toml"
    save(one_room(), world)
    out = tmp_path / "g.mcap"
    args = ["record", "--ros1", str(pkg), "--node", "plugin", "--scenario", str(world)]
    code = main([*args, "--out", str(out)])
    text = capsys.readouterr().out
    assert code == 4, text
    assert "hint: gazebo/gazebo.hh: usar has no Gazebo: use cmd_vel, /odom and /tf" in text, text
    assert open_run(out).outcome == "build_failed"
