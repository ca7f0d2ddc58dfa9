"""code/compile: a syntax-only build says compiles / warnings / cannot tell."""

from __future__ import annotations

import shutil

import pytest

from usar_replay.code.compile import compile_check, parse_output
from usar_replay.code.sources import Source

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
