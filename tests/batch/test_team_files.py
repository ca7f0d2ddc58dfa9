"""batch/team_files: a team's folder digested on real files, refusing what would hang or
blow up a plain read."""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import pytest

from usar_replay.batch.team_files import MAX_FILE_BYTES, UnusableSubmission, submission_digest


def _team(root: Path) -> Path:
    (root / "pkg").mkdir(parents=True)
    (root / "mission.py").write_text("def main(): pass\n", encoding="utf-8")
    (root / "pkg" / "helper.py").write_text("X = 1\n", encoding="utf-8")
    return root


def test_the_digest_is_stable_and_covers_every_file(tmp_path: Path) -> None:
    team = _team(tmp_path / "a")
    first = submission_digest(team)
    assert submission_digest(_team(tmp_path / "b")) == first  # the same bytes, another folder
    (team / "pkg" / "helper.py").rename(team / "pkg" / "other.py")
    assert submission_digest(team) != first  # a name is part of the digest


def test_caches_and_hidden_files_are_left_out(tmp_path: Path) -> None:
    team = _team(tmp_path / "a")
    before = submission_digest(team)
    (team / "m.pyc").write_bytes(b"\0")
    (team / ".git").mkdir()
    (team / ".git" / "HEAD").write_text("ref\n", encoding="utf-8")
    (team / ".notes").write_text("x", encoding="utf-8")
    os.mkfifo(team / ".hidden_fifo")  # hidden: never opened
    assert submission_digest(team) == before


def test_a_single_file_is_digested_as_its_bytes(tmp_path: Path) -> None:
    path = tmp_path / "mission.py"
    path.write_bytes(b"print(1)\n")
    assert submission_digest(path) == hashlib.sha256(b"print(1)\n").hexdigest()


def test_a_link_inside_is_its_text_and_a_link_out_is_refused(tmp_path: Path) -> None:
    team = _team(tmp_path / "a")
    (team / "alias.py").symlink_to("mission.py")
    with_link = submission_digest(team)
    assert with_link != submission_digest(_team(tmp_path / "b"))
    (team / "zero").symlink_to("/dev/zero")
    with pytest.raises(UnusableSubmission, match=r"zero: a link leaving the team's folder"):
        submission_digest(team)


def test_a_fifo_is_refused_not_read(tmp_path: Path) -> None:
    team = _team(tmp_path / "a")
    os.mkfifo(team / "pkg" / "pipe")
    with pytest.raises(UnusableSubmission, match=r"pkg/pipe: not a regular file"):
        submission_digest(team)


def test_a_sparse_file_over_the_cap_is_refused_unread(tmp_path: Path) -> None:
    team = _team(tmp_path / "a")
    with open(team / "big.bin", "wb") as f:
        f.truncate(MAX_FILE_BYTES + 1)  # sparse: no disk, no time
    with pytest.raises(UnusableSubmission, match=rf"big.bin: {MAX_FILE_BYTES + 1} bytes"):
        submission_digest(team)


def test_submission_digest_covers_helpers_not_caches(tmp_path: Path) -> None:
    team = tmp_path / "t"
    team.mkdir()
    (team / "mission.py").write_text("import helper\n")
    (team / "helper.py").write_text("X = 1\n")
    first = submission_digest(team)
    (team / "__pycache__").mkdir()
    (team / "__pycache__" / "helper.cpython-311.pyc").write_bytes(b"\0")
    assert submission_digest(team) == first
    (team / "helper.py").write_text("X = 2\n")
    assert submission_digest(team) != first
