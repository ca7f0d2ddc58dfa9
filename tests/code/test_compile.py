"""code/compile: a syntax-only build says compiles / warnings / cannot tell."""

from __future__ import annotations

import shutil

import pytest

from usar_replay.code.compile import compile_check, diagnostics, from_build, parse_output
from usar_replay.code.sources import Source
from usar_replay.ros1.building.workspace import WARNING_FLAGS

needs = pytest.mark.skipif(shutil.which("g++") is None, reason="needs g++")


@needs
def test_clean_warned_and_broken() -> None:
    clean = compile_check([Source("src/a.cpp", "int main() { return 0; }\n")])
    assert (clean.compiles, clean.warnings, clean.clean) == (True, 0, True)
    warned = compile_check([Source("src/a.cpp", "int main() { int unused = 1; return 0; }\n")])
    assert (warned.compiles, warned.clean, warned.where) == (True, False, "src/a.cpp:1")
    broken = compile_check([Source("src/a.cpp", "int main() { return nope; }\n")])
    assert broken.compiles is False and broken.where == "src/a.cpp:1"


@needs
def test_a_header_found_nowhere_leaves_it_unknown() -> None:
    got = compile_check([Source("src/a.cpp", "#include <fiducial_msgs/Nope.h>\nint x;\n")])
    assert got.compiles is None and "header fiducial_msgs/Nope.h not found" in got.problem


def test_the_compilers_lines_are_read() -> None:
    out = (
        "src/b.cpp:3:5: warning: unused variable 'x' [-Wunused-variable]\n"
        "src/b.cpp:9:1: error: expected ';'\n"
    )
    assert parse_output(out) == (1, 1, "b.cpp:9", "")


def test_without_gxx_it_says_what_to_install(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("PATH", "/nonexistent")
    assert compile_check([]).problem == "g++ is not installed: apt-get install g++"


ROOT = "/ros1/ws/src/pkg"
BUILD = f"""[ 50%] Building CXX object pkg/CMakeFiles/node.dir/src/main.cpp.o
In file included from {ROOT}/src/main.cpp:2:
{ROOT}/include/pkg/robot.h:4:7: warning: unused variable 'a' [-Wunused-variable]
/usr/include/ros/node_handle.h:10:1: warning: a system header's [-Wdeprecated]
/ros1/ws/devel/include/pkg/Msg.h:7:1: warning: a generated header's [-Wunused-parameter]
{ROOT}/src/main.cpp:9:3: warning: unused variable 'b' [-Wunused-variable]
{ROOT}/src/main.cpp:9:3: note: declared here
{ROOT}/src/../src/explorer.cpp:3:12: warning: unused parameter 'c' [-Wunused-parameter]
[100%] Linking CXX executable /ros1/ws/devel/lib/pkg/node
"""


def test_a_builds_warnings_are_those_of_the_packages_own_files() -> None:
    """A system header's and a generated header's lines are not the team's; the places are in
    file and line order (a parallel make prints its units in any order)."""
    got = from_build(BUILD, ROOT, False, WARNING_FLAGS)
    assert (got.compiles, got.clean, got.warnings) == (True, False, 3)
    assert got.where == "include/pkg/robot.h:4; src/explorer.cpp:3; src/main.cpp:9"
    assert got.note == "the demo's catkin_make (-Wall -Wextra added)"
    shuffled = "\n".join(reversed(BUILD.splitlines()))
    assert from_build(shuffled, ROOT, False, WARNING_FLAGS) == got
    clean = from_build("[100%] Built target node\n", ROOT + "/", False, WARNING_FLAGS)
    assert (clean.compiles, clean.clean, clean.where) == (True, True, "")
    own = from_build("", ROOT, False, ())
    assert "its own flags (its CMake files ask for -Werror)" in own.note
    assert [d.where for d in diagnostics(BUILD, ROOT)] == [
        "include/pkg/robot.h:4", "src/main.cpp:9", "src/explorer.cpp:3"
    ]  # as printed, the path made plain


def test_a_failed_build_does_not_compile_and_says_where() -> None:
    broken = f"{ROOT}/src/main.cpp:3:10: fatal error: nope.h: No such file or directory\n"
    got = from_build(BUILD + broken, ROOT, True, WARNING_FLAGS)
    assert (got.compiles, got.clean, got.where) == (False, False, "src/main.cpp:3")
    assert got.note == "the demo's catkin_make (-Wall -Wextra added) failed"
    cmake = "CMake Error at pkg/CMakeLists.txt:3 (find_package):\n  Could not find nope\n"
    assert from_build(cmake, ROOT, True, WARNING_FLAGS).where == "CMakeLists.txt:3"
    assert from_build("make: *** [all] Error 2\n", ROOT, True, ()).where == ""


@needs
def test_an_unterminated_comment_does_not_compile_with_the_compilers_first_error() -> None:
    """A header that opens a comment it never closes compiles nowhere: ``compiles`` false with
    the compiler's first error, even where a header it includes is also missing (issue 51)."""
    header = Source("include/pkg/robot.h", "#pragma once\n/* the robot\nclass Robot {};\n")
    unit = Source("src/main.cpp", '#include "pkg/robot.h"\nint main() { return 0; }\n')
    got = compile_check([header, unit])
    assert got.compiles is False and got.where == "include/pkg/robot.h:2"
    assert got.note == "include/pkg/robot.h:2: error: unterminated comment"
    also = Source("src/main.cpp", '#include "pkg/robot.h"\n#include <nope/Nope.h>\nint x;\n')
    assert compile_check([header, also]).compiles is False


@needs
@pytest.mark.slow
def test_a_course_package_compiles_against_usars_underlay() -> None:
    """``fiducial_msgs`` (which Debian lacks) from usar's underlay, the course machine usar
    builds the demo on: the course package compiles, its warnings counted (issue 51: every
    real package stopped at ``fiducial_msgs/FiducialTransformArray.h not found``)."""
    from pathlib import Path

    from usar_replay.code.compile import message_includes
    from usar_replay.code.sources import read_submission

    includes = message_includes()
    assert includes and (includes[0] / "fiducial_msgs" / "FiducialTransformArray.h").is_file()
    sub = read_submission(Path(__file__).resolve().parents[2] / "examples/ros1/usar_course")
    assert any("fiducial_msgs/FiducialTransformArray.h" in s.text for s in sub.sources)
    got = compile_check(sub.sources, includes)
    assert got.compiles is True, got
    assert "not found" not in got.problem
