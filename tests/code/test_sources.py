"""code/sources: a team's files read without trusting them; a bad file is a finding."""

from __future__ import annotations

import os
from pathlib import Path

import codetools
import pytest

from usar_replay.code.sources import MAX_SOURCE_BYTES, read_submission
from usar_replay.core.errors import UnusableSubmission, UsarError


def test_a_repository_with_the_package_in_a_subfolder(tmp_path: Path) -> None:
    codetools.alpha(tmp_path / "repo" / "catkin_ws" / "src" / "final_project")
    (tmp_path / "repo" / "report.pdf").write_bytes(b"%PDF-1.4\n")
    sub = read_submission(tmp_path / "repo", "team1")
    assert sub.name == "team1" and sub.package_name == "final_project"
    assert sub.package_prefix == "catkin_ws/src/final_project"
    assert [s.rel for s in sub.sources] == [
        "include/alpha/robots.h", "src/main.cpp", "src/robots.cpp"
    ]  # fmt: skip
    assert "report.pdf" in sub.files
    assert "doc/instructions.txt" in sub.package_files()


def test_binary_non_utf8_huge_and_linked_files_are_findings(tmp_path: Path) -> None:
    pkg = codetools.beta(tmp_path / "t")
    (pkg / "src" / "bin.cpp").write_bytes(b"int a;\0\0\0")
    (pkg / "src" / "latin.cpp").write_bytes(b"// caf\xe9\nint b;\n")
    (pkg / "src" / "huge.cpp").write_bytes(b"/" * (MAX_SOURCE_BYTES + 1))
    os.symlink("main.cpp", pkg / "src" / "link.cpp")
    sub = read_submission(pkg)
    assert [s.rel for s in sub.sources] == ["src/main.cpp"]
    said = "\n".join(sub.findings)
    assert "bin.cpp: binary" in said and "latin.cpp: not UTF-8" in said
    assert "huge.cpp: " in said and "link.cpp: a link" in said


def test_a_fifo_or_a_link_out_is_the_teams_verdict(tmp_path: Path) -> None:
    pkg = codetools.beta(tmp_path / "t")
    os.mkfifo(pkg / "src" / "pipe.cpp")
    with pytest.raises(UnusableSubmission, match="not a regular file"):
        read_submission(pkg)
    (pkg / "src" / "pipe.cpp").unlink()
    os.symlink("/etc/passwd", pkg / "src" / "out.h")
    with pytest.raises(UnusableSubmission, match="a link leaving"):
        read_submission(pkg)


def test_no_package_is_a_one_line_error(tmp_path: Path) -> None:
    (tmp_path / "empty").mkdir()
    with pytest.raises(UsarError, match="no package\\.xml"):
        read_submission(tmp_path / "empty")
