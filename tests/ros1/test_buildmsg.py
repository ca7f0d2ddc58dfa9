"""ros1/buildmsg: a failed build's lines in the student's folder, its errors, and a hint."""

from __future__ import annotations

from pathlib import Path

from usar_replay.ros1 import buildmsg


def test_hints_and_paths_for_a_missing_dependency_and_an_own_message() -> None:
    missing = 'Could not find a package configuration file provided by "tf3_ros" with any'
    assert "'tf3_ros' is not installed here" in buildmsg.hint(missing, "pkg")
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
