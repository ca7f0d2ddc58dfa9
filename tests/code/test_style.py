"""code/style: formatting against Google style at the file's own indentation width."""

from __future__ import annotations

import shutil

import pytest

from usar_replay.code.sources import Source
from usar_replay.code.style import course_style, indent_width, style

needs = pytest.mark.skipif(shutil.which("clang-format") is None, reason="needs clang-format")

TWO = "int f(int a) {\n  if (a > 1) {\n    return a;\n  }\n  return 0;\n}\n"
FOUR = TWO.replace("  ", "    ")
MESSY = "int f(int a){\nif(a>1){return a;}\n  return 0 ;}\n"


def test_indent_width_is_the_files_own() -> None:
    assert indent_width(TWO) == 2 and indent_width(FOUR) == 4
    assert indent_width("int a;\n") == 2


def test_the_style_keeps_the_width_asked() -> None:
    assert "IndentWidth: 4" in course_style(4) and "BasedOnStyle: Google" in course_style(4)


@needs
def test_four_space_indents_are_not_counted_but_messy_code_is() -> None:
    assert style([Source("a.cpp", TWO)]).changed_share == 0.0
    assert style([Source("a.cpp", FOUR)]).changed_share == 0.0
    messy = style([Source("a.cpp", MESSY)])
    assert messy.changed_lines == 3 and messy.worst == "a.cpp:1"


def test_without_clang_format_it_says_what_to_install(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("PATH", "/nonexistent")
    got = style([Source("a.cpp", TWO)])
    assert got.changed_share is None
    assert got.problem == "clang-format is not installed: apt-get install clang-format"
