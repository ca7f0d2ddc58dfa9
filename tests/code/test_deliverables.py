"""code/deliverables: the Doxyfile and the instructions, where the handout asks for them."""

from __future__ import annotations

from pathlib import Path

import codetools

from usar_replay.code.deliverables import deliverables
from usar_replay.code.sources import read_submission


def test_doc_instructions_and_a_doxyfile(tmp_path: Path) -> None:
    got = deliverables(read_submission(codetools.alpha(tmp_path / "a")))
    assert (got.doxyfile, got.instructions, got.instructions_at) == (
        "Doxyfile", "doc", "doc/instructions.txt"
    )  # fmt: skip


def test_instructions_elsewhere_and_none(tmp_path: Path) -> None:
    root = tmp_path / "team"
    codetools.beta(root / "final_project")
    assert deliverables(read_submission(root)).instructions == "none"
    (root / "INSTRUCTIONS.md").write_text("run it\n")
    got = deliverables(read_submission(root))
    assert (got.instructions, got.instructions_at) == ("elsewhere", "INSTRUCTIONS.md")


def test_a_readme_that_says_how_to_run_is_instructions_elsewhere(tmp_path: Path) -> None:
    pkg = codetools.beta(tmp_path / "b")
    (pkg / "README.md").write_text("# Team\n\n    roslaunch final_project go.launch\n")
    assert deliverables(read_submission(pkg)).instructions == "elsewhere"
