"""code/cppcheck: unused functions and unread variables found, the template's not counted."""

from __future__ import annotations

import shutil

import codetools
import pytest

from usar_replay.code.cppcheck import UNREAD, UNUSED, findings, parse_xml
from usar_replay.code.sources import Source

needs = pytest.mark.skipif(shutil.which("cppcheck") is None, reason="needs cppcheck")


@needs
def test_unused_functions_and_an_unread_variable() -> None:
    got = findings([Source("src/main.cpp", codetools.PROCEDURAL_MAIN)])
    assert got.problem == ""
    assert sorted(f.symbol for f in got.of(UNUSED)) == [
        "helper_two", "never_called", "unused_counter"
    ]  # fmt: skip
    assert [(f.symbol, f.line) for f in got.of(UNREAD)] == [("unread", 17)]


@needs
def test_the_templates_functions_are_not_unused() -> None:
    got = findings([Source("src/main.cpp", codetools.PROCEDURAL_MAIN)],
                   frozenset({"helper_two", "never_called"}))  # fmt: skip
    assert [f.symbol for f in got.of(UNUSED)] == ["unused_counter"]


@needs
def test_a_clean_package_has_none() -> None:
    got = findings([Source("src/main.cpp", codetools.BORROWED_MAIN)])
    assert got.of(UNUSED) == [] and got.of(UNREAD) == [] and got.lint() == []


def test_its_own_notes_are_not_lint() -> None:
    xml = (
        '<results version="2"><errors>'
        '<error id="missingIncludeSystem" severity="information" msg="m"/>'
        '<error id="passedByValue" severity="performance" msg="p">'
        '<location file="src/a.cpp" line="3"/><symbol>v</symbol></error>'
        "</errors></results>"
    )
    got = parse_xml(xml)
    assert [(f.id, f.file, f.line) for f in got] == [
        ("missingIncludeSystem", "", 0), ("passedByValue", "a.cpp", 3)
    ]  # fmt: skip
    assert parse_xml("not xml") == []


def test_without_cppcheck_it_says_what_to_install(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("PATH", "/nonexistent")
    got = findings([Source("a.cpp", "int a;\n")])
    assert got.problem == "cppcheck is not installed: apt-get install cppcheck"


def test_a_report_cut_at_its_size_is_the_teams_failure(monkeypatch: pytest.MonkeyPatch) -> None:
    """Thousands of findings cut the XML: read as it is, it would be fewer (or none)."""
    import usar_replay.code.cppcheck as cc
    from usar_replay.code.tools import Ran

    monkeypatch.setattr(cc, "missing", lambda _tool: "")
    monkeypatch.setattr(cc, "run_tool", lambda *_a, **_k: Ran(0, "", "<results><err", "", True))
    got = findings([Source("a.cpp", "int a;\n")])
    assert got.items == () and got.problem.startswith("cppcheck exceeded its report's size")

