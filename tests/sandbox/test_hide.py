"""sandbox/hide: the grader's files found by what they are (real paths, hard links) in real
folders, so the sandbox can hide them."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from usar_replay.core.errors import UsageError
from usar_replay.sandbox import hide


def _mission(root: Path) -> Path:
    (root / "pkg").mkdir(parents=True)
    (root / "mission.py").write_text("def main(): pass\n", encoding="utf-8")
    return root


def test_given_files_and_folders_are_hidden_by_their_real_paths(tmp_path: Path) -> None:
    team = _mission(tmp_path / "team")
    world = team / "world.toml"
    world.write_text("", encoding="utf-8")
    (team / "alias.toml").symlink_to(world)
    files, folders = hide.grader_files(
        [str(team / "pkg" / ".." / "alias.toml"), str(team / "pkg"), "", str(team / "gone.json")],
        [str(team)],
    )
    assert files == (str(world),)
    assert folders == (str(team / "pkg"),)


def test_another_name_of_a_hard_linked_file_is_found(tmp_path: Path) -> None:
    team = _mission(tmp_path / "team")
    key = tmp_path / "world.key"
    key.write_text("secret", encoding="utf-8")
    os.link(key, team / "pkg" / "data.bin")
    files, _ = hide.grader_files([str(key)], [str(team)])
    assert files == (str(key), str(team / "pkg" / "data.bin"))
    files, _ = hide.grader_files([str(team / "mission.py")], [str(team)])
    assert files == (str(team / "mission.py"),)  # one link: nothing searched


def test_a_folder_too_large_to_search_is_refused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    team = _mission(tmp_path / "team")
    for i in range(30):
        (team / f"f{i}").write_bytes(b"")
    key = tmp_path / "k"
    key.write_text("x", encoding="utf-8")
    os.link(key, tmp_path / "k2")
    monkeypatch.setattr(hide, "MAX_SEARCHED", 10)  # the bound, small enough for a test folder
    with pytest.raises(UsageError, match=r"has another name \(a hard link\) and .* too large"):
        hide.grader_files([str(key)], [str(team)])
