"""The build as a student meets it (issue 28, point 1 and 2): a package written for a course
machine (Debian's ROS 1 plus an installed ``fiducial_msgs``) builds under usar as it is, a build
error points into the student's folder with a hint, and ``usar record`` prints the build's time
apart from the run's.

Real catkin builds of a one-file C++ node (Debian 12's ROS 1 and bubblewrap: CI installs both).
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from catkintools import cxx_package
from conftest import one_room

from usar_replay.cli.main import main
from usar_replay.log.run import open_run
from usar_replay.ros1.building.workspace import (
    WARNING_FLAGS,
    BuildFailed,
    cached_build,
    find_package,
    private_build,
    remove_tree,
)
from usar_replay.world.scenario_toml import save

NODE = """
#include <ros/ros.h>
#include <fiducial_msgs/FiducialTransformArray.h>

int main(int argc, char** argv) {
  ros::init(argc, argv, "plain");
  ros::NodeHandle nh;
  int seen = 0;
  ros::Subscriber sub = nh.subscribe<fiducial_msgs::FiducialTransformArray>(
      "/fiducial_transforms", 10,
      [&seen](const fiducial_msgs::FiducialTransformArray::ConstPtr&) {
        if (++seen >= 3) ros::shutdown();
      });
  ros::spin();
  return 0;
}
"""

# as on a course machine: no add_dependencies(... ${catkin_EXPORTED_TARGETS}) for fiducial_msgs
CMAKE = """cmake_minimum_required(VERSION 3.0.2)
project(plain)
find_package(catkin REQUIRED COMPONENTS {components})
catkin_package()
include_directories(${{catkin_INCLUDE_DIRS}})
add_executable(plain_node src/main.cpp)
target_link_libraries(plain_node ${{catkin_LIBRARIES}})
"""


@pytest.fixture(autouse=True, scope="module")
def _cache(own_build_cache: Path) -> None:
    """One build cache for this module (tests/conftest.py)."""


def plain(folder: Path, components: str) -> Path:
    (folder / "src").mkdir(parents=True)
    (folder / "launch").mkdir()
    (folder / "package.xml").write_text(
        '<?xml version="1.0"?>\n<package format="2"><name>plain</name><version>0.0.1</version>'
        "<description>plain</description><maintainer email='p@p.invalid'>p</maintainer>"
        "<license>MIT</license><buildtool_depend>catkin</buildtool_depend>"
        "<depend>roscpp</depend><depend>fiducial_msgs</depend></package>\n",
        encoding="utf-8",
    )
    (folder / "CMakeLists.txt").write_text(CMAKE.format(components=components), encoding="utf-8")
    (folder / "src" / "main.cpp").write_text(NODE, encoding="utf-8")
    (folder / "launch" / "plain.launch").write_text(
        '<launch><node pkg="plain" type="plain_node" name="plain" required="true"/></launch>\n',
        encoding="utf-8",
    )
    return folder


def _record(
    tmp_path: Path, pkg: Path, name: str, capsys: pytest.CaptureFixture[str]
) -> tuple[int, str, Path]:
    world = tmp_path / "room.toml"
    if not world.exists():
        save(one_room(), world)
    out = tmp_path / f"{name}.mcap"
    args = ["record", "--ros1", str(pkg), "--scenario", str(world), "--out", str(out), "--quiet"]
    code = main([*args, "--max-sim-time", "5"])
    return code, capsys.readouterr().out, out


def test_a_package_without_add_dependencies_builds_and_runs(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """fiducial_msgs is an underlay, as installed on a course machine: the package needs no
    add_dependencies. The build's time is printed apart from the run's; a second run says
    ``cached``."""
    pkg = plain(tmp_path / "plain", "roscpp fiducial_msgs")
    code, text, out = _record(tmp_path, pkg, "first", capsys)
    run = open_run(out)
    assert code == 0 and run.outcome == "done", (text, run.outcome_reason)
    assert re.search(r"^Build: catkin_make \d+\.\d s \(not counted", text, re.M), text
    code, text, _ = _record(tmp_path, pkg, "second", capsys)
    assert code == 0, text
    assert "Build: cached (not counted in the run's wall time)" in text


def test_a_missing_find_package_component_says_what_to_change(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """fiducial_msgs left out of find_package: the compiler's error names the student's own
    file, and one line says what to add."""
    pkg = plain(tmp_path / "plain", "roscpp")
    code, text, out = _record(tmp_path, pkg, "broken", capsys)
    assert code == 4, text
    mine = str((pkg / "src" / "main.cpp").resolve())
    assert f"{mine}:3:" in text and "fiducial_msgs/FiducialTransformArray.h" in text, text
    assert ".cache" not in text and "/ws/src/" not in text, text
    hint = "hint: add fiducial_msgs to find_package(catkin REQUIRED COMPONENTS ...) and package.xml"
    assert hint in text.splitlines(), text
    assert open_run(out).outcome == "build_failed"


UNUSED = "\n  int unused = 3;"
"""A line of the team's that ``-Wall`` warns about (``main.cpp:6``)."""


def test_the_builds_output_is_kept_with_its_cache_entry(tmp_path: Path) -> None:
    """The build is given -Wall -Wextra and its output is kept: a cache hit says what the build
    said, and a build of its own (no cache) the same of the package's own files."""
    pkg = find_package(cxx_package(tmp_path / "warned", "warned", UNUSED))
    first = cached_build(pkg, fixed=True)
    assert not first.cached and first.flags == WARNING_FLAGS
    assert first.source_root == "/ros1/ws/src/warned"
    said = f"{first.source_root}/src/main.cpp:6:7: warning: unused variable"
    assert said in first.output, first.output
    hit = cached_build(pkg, fixed=True)
    assert hit.cached and (hit.output, hit.flags) == (first.output, first.flags)
    own, holder = private_build(pkg, fixed=True)
    try:
        assert said in own.output and own.flags == WARNING_FLAGS
    finally:
        remove_tree(holder)


def test_a_package_asking_for_werror_is_built_with_its_own_flags(tmp_path: Path) -> None:
    """-Wall added to -Werror would fail a build that builds on a course machine."""
    folder = cxx_package(tmp_path / "strict", "strict", UNUSED, "add_compile_options(-Werror)")
    built = cached_build(find_package(folder))
    assert built.flags == () and "warning:" not in built.output


def test_a_failed_build_keeps_its_output(tmp_path: Path) -> None:
    pkg = find_package(cxx_package(tmp_path / "broken", "broken", "\n  return nope;"))
    with pytest.raises(BuildFailed) as failed:
        cached_build(pkg, fixed=True)
    assert failed.value.verdict == "build_failed" and failed.value.flags == WARNING_FLAGS
    assert f"{failed.value.root}/src/main.cpp:6:10: error: " in failed.value.output
