"""code/doxygen: classes, functions and whether each is documented, from doxygen's XML."""

from __future__ import annotations

import shutil
from pathlib import Path

import codetools
import pytest

from usar_replay.code.doxygen import symbols
from usar_replay.code.sources import Source

pytestmark = pytest.mark.skipif(shutil.which("doxygen") is None, reason="needs doxygen")


def test_alpha_is_documented_with_two_classes_and_a_thin_main() -> None:
    found = symbols([
        Source("include/alpha/robots.h", codetools.ALPHA_H),
        Source("src/robots.cpp", codetools.ALPHA_CPP),
        Source("src/main.cpp", codetools.ALPHA_MAIN),
    ])  # fmt: skip
    assert found.problem == ""
    classes = {s.name: s for s in found.items if s.kind == "class"}
    assert set(classes) == {"alpha::Explorer", "alpha::Follower"}
    assert classes["alpha::Explorer"].methods == 5
    functions = [s for s in found.items if s.kind == "function"]
    assert all(s.documented for s in functions), [s.name for s in functions if not s.documented]
    main = next(s for s in functions if s.name == "main")
    assert (main.file, main.body_lines) == ("src/main.cpp", 14)
    step = next(s for s in functions if s.name == "alpha::Explorer::step")
    assert step.file == "src/robots.cpp" and step.body_lines > 5


def test_an_undocumented_procedural_package_has_no_class() -> None:
    found = symbols([Source("src/main.cpp", codetools.PROCEDURAL_MAIN)])
    assert [s for s in found.items if s.kind == "class"] == []
    assert not any(s.documented for s in found.items)
    assert len(found.items) == 5


def test_without_doxygen_it_says_what_to_install(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("PATH", "/nonexistent")
    found = symbols([Source("src/main.cpp", "int main() {}\n")])
    assert found.items == ()
    assert found.problem == "doxygen is not installed: apt-get install doxygen"


def test_xml_that_cannot_be_read_is_an_error_not_fewer_symbols(tmp_path: Path) -> None:
    from usar_replay.code.doxygen import parse_xml

    (tmp_path / "classA.xml").write_text("<doxygen><compounddef kind='class'>")
    with pytest.raises(ValueError, match=r"classA\.xml"):
        parse_xml(tmp_path)
