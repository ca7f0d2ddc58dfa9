"""ros1/buildmsg: a failed build's lines in the student's folder, its errors, and a hint."""

from __future__ import annotations

from pathlib import Path

from usar_replay.ros1.building import message as buildmsg


def test_hints_and_paths_for_a_missing_dependency_and_an_own_message() -> None:
    missing = 'Could not find a package configuration file provided by "tf3_ros" with any'
    assert buildmsg.hint(missing, "pkg") == (
        "hint: no Debian 12 package provides 'tf3_ros': check its name in find_package(...)"
    )
    own = "src/a.cpp:2:10: fatal error: pkg/Thing.h: No such file or directory"
    assert "add_dependencies(TARGET ${${PROJECT_NAME}_EXPORTED_TARGETS})" in buildmsg.hint(
        own, "pkg"
    )
    unlinked = "a.cpp:(.text+0x1): undefined reference to `tf2_ros::TransformBroadcaster::X()'"
    assert "link tf2_ros: add it to find_package" in buildmsg.hint(unlinked, "pkg")
    said = "CMake Error at pkg/CMakeLists.txt:6 (message):\n/ws/src/pkg/a.cpp:1: error"
    mapped = buildmsg.student_paths(said, Path("/ws/src/pkg"), Path("/home/me/pkg"))
    assert (
        mapped
        == "CMake Error at /home/me/pkg/CMakeLists.txt:6 (message):\n/home/me/pkg/a.cpp:1: error"
    )
    assert buildmsg.hint("all fine", "pkg") == ""
    for said in (missing, own, unlinked):
        assert len(buildmsg.hint(said, "a_package_name")) <= 100


def test_errors_keeps_the_marked_lines_and_the_two_after_once() -> None:
    output = "\n".join(
        [
            "Scanning dependencies",
            "a.cpp:3:1: error: 'x' was not declared",
            "    x = 1;",
            "    ^",
            "[ 50%] Building",
            "a.cpp:9:1: error: expected ';'",
            "make: *** [all] Error 2",
            "done",
        ]
    )
    assert buildmsg.errors(output).splitlines() == [
        "a.cpp:3:1: error: 'x' was not declared",
        "    x = 1;",
        "    ^",
        "a.cpp:9:1: error: expected ';'",
        "make: *** [all] Error 2",
        "done",
    ]
    assert len(buildmsg.errors(output, limit=2).splitlines()) == 2


def test_errors_without_a_marked_line_are_the_last_lines() -> None:
    output = "\n".join(f"line {i}" for i in range(100))
    assert buildmsg.errors(output, limit=3) == "line 97\nline 98\nline 99"


def test_an_unknown_namespace_is_named_as_it_is() -> None:
    said = "undefined reference to `my_lib::helper()'"
    assert buildmsg.hint(said, "pkg") == (
        "hint: link my_lib: add it to find_package(catkin REQUIRED COMPONENTS ...)"
    )
    ros = "undefined reference to `ros::init(int&, char**)'"
    assert "link roscpp:" in buildmsg.hint(ros, "pkg")


def test_a_ros_package_debian_has_is_named_with_its_apt_line() -> None:
    """Issue 31: the course template's ``tf`` without libtf-dev said "check its name"; the
    name is right, the Debian package is missing."""
    catkin = (
        "-- Could not find the required component 'tf'. The following CMake error indicates "
        "that you either need to install the package with the same name or change your "
        "environment so that it can be found.\nCMake Error at /usr/share/catkin/cmake/"
        "catkinConfig.cmake:82 (find_package):\n  Could not find a package configuration file"
        ' provided by "tf" with any\n  of the following names:'
    )
    assert buildmsg.hint(catkin, "final_project") == (
        "hint: install tf: apt-get install -y --no-install-recommends libtf-dev"
    )
    plain = 'Could not find a package configuration file provided by "laser_geometry" with'
    assert buildmsg.hint(plain, "p").endswith(
        "apt-get install -y --no-install-recommends liblaser-geometry-dev"
    )
    for ros, deb in (
        ("std_srvs", "libstd-srvs-dev"),
        ("cv_bridge", "libcv-bridge-dev"),
        ("pcl_ros", "libpcl-ros-dev"),
        ("rosgraph_msgs", "libros-rosgraph-msgs-dev"),
    ):
        said = buildmsg.hint(f"Could not find the required component '{ros}'.", "p")
        assert said == f"hint: install {ros}: apt-get install -y --no-install-recommends {deb}"
        assert len(said) <= 100


def test_what_debian_lacks_says_what_usar_does_instead() -> None:
    nav = buildmsg.hint("Could not find the required component 'costmap_2d'.", "p")
    assert nav.startswith("hint: costmap_2d: ROS navigation, not in Debian 12; usar's move_base")
    assert "remove it from find_package(...)" in nav
    gz = buildmsg.hint('Could not find a package configuration file provided by "gazebo"', "p")
    assert gz == "hint: gazebo: usar has no Gazebo: use cmd_vel, /odom and /tf, not Gazebo's API"


def test_gazebo_api_and_stand_in_headers_get_their_own_hint() -> None:
    """A plugin or node that includes Gazebo's headers cannot build here: usar has no Gazebo;
    a stand-in package is a name only."""
    said = "/ws/src/p/src/plugin.cpp:1:10: fatal error: gazebo/gazebo.hh: No such file or dir"
    got = buildmsg.hint(said, "p")
    assert got.startswith("hint: gazebo/gazebo.hh: usar has no Gazebo") and len(got) <= 100
    msgs = "a.cpp:3:10: fatal error: gazebo_msgs/ModelStates.h: No such file or directory"
    assert "usar has no Gazebo" in buildmsg.hint(msgs, "p")
    amcl = "a.cpp:3:10: fatal error: move_base/move_base.h: No such file or directory"
    assert buildmsg.hint(amcl, "p") == (
        "hint: usar's move_base is a name only, for navigation: usar's move_base action servers"
    )


def test_a_carriage_return_in_a_builds_error_starts_no_line() -> None:
    """A red team's ``message(FATAL_ERROR "...\\r usar: exit 0: 60/60 PASS")`` (issue 44):
    the error is one line, the carriage return shown, never obeyed."""
    from usar_replay.ros1.building.message import errors

    output = "CMake Error at CMakeLists.txt:3 (message):\n  oops\rusar: exit 0: 60/60 PASS\x1b[2K\n"
    shown = errors(output)
    assert not any(line.startswith("usar:") for line in shown.split("\n")), shown
    assert "oops\\x0dusar: exit 0" in shown and "\x1b" not in shown and "\r" not in shown
