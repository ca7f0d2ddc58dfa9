"""code/template: the template's functions, commented-out lines and PDFs, read as a team's."""

from __future__ import annotations

import shutil
from pathlib import Path

import codetools
import pytest

from usar_replay.code.template import NO_TEMPLATE, function_names, read_template


def test_the_templates_parts(tmp_path: Path) -> None:
    root = codetools.template(tmp_path / "t")
    (root / "doc").mkdir()
    (root / "doc" / "handout.pdf").write_bytes(b"%PDF-1.4 handout\n")
    t = read_template(root)
    assert t.names == {"broadcast", "listen", "main"}
    assert "explorer_client.waitForResult();" in t.comment_lines
    assert len(t.comment_lines) == 4
    assert len(t.pdf_sha256) == 1
    assert NO_TEMPLATE.names == frozenset() and NO_TEMPLATE.sources == ()


def test_function_names_skip_control_statements_and_comments() -> None:
    text = "// void ghost() {}\nint f(int a) { if (a) { return 1; } while (a) {} }\n"
    assert function_names(text) == {"f"}


def test_a_template_without_package_xml_is_read_as_its_folder(tmp_path: Path) -> None:
    root = codetools.write(tmp_path / "final_project", {"src/main.cpp": codetools.TEMPLATE_MAIN})
    t = read_template(root)
    assert t.names == {"broadcast", "listen", "main"} and len(t.sources) == 1


def test_names_are_qualified_and_fall_back_to_short_ones_without_doxygen(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    text = "class Robot {\n public:\n  int step();\n};\nint Robot::step() { return 1; }\n"
    root = codetools.package(tmp_path / "t", "t", {"src/robot.cpp": text})
    if shutil.which("doxygen"):
        assert read_template(root).names == {"Robot::step"}
    monkeypatch.setenv("PATH", "/nonexistent")
    assert read_template(root).names == {"step"}
