"""core/folder_walk: one walk of a handed-in folder decides what is read, on real files."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from usar_replay.core.errors import UnusableSubmission
from usar_replay.core.folder_walk import MAX_FILE_BYTES, linked, shown, stream, walk


def _folder(root: Path) -> Path:
    (root / "src").mkdir(parents=True)
    (root / "CMakeLists.txt").write_text("project(x)\n", encoding="utf-8")
    (root / "src" / "main.cpp").write_text("int main() {}\n", encoding="utf-8")
    return root


def test_names_are_bytes_and_a_name_that_is_not_utf8_is_walked(tmp_path: Path) -> None:
    root = _folder(tmp_path / "team")
    os.close(os.open(os.fsencode(root) + b"/caf\xe9.txt", os.O_CREAT | os.O_WRONLY, 0o644))
    rels = [e.rel for e in walk(root)]
    assert rels == [b"CMakeLists.txt", b"caf\xe9.txt", b"src/main.cpp"]
    assert shown(b"caf\xe9.txt") == "caf\\xe9.txt"
    assert shown("a\x1b[2Jb") == "a\\x1b[2Jb"  # a name never drives the terminal


def test_hidden_names_caches_and_skipped_folders_are_never_read(tmp_path: Path) -> None:
    root = _folder(tmp_path / "team")
    (root / ".cache").mkdir()
    with open(root / ".cache" / "blob.bin", "wb") as f:
        f.truncate(2 * 1024**3)  # 2 GiB, sparse: over every cap, but hidden
    os.mkfifo(root / ".pipe")
    (root / "build").mkdir()
    os.mkfifo(root / "build" / "fifo")
    (root / "m.pyc").write_bytes(b"\0")
    assert [e.rel for e in walk(root, skip_dirs=frozenset({"build"}))] == [
        b"CMakeLists.txt",
        b"src/main.cpp",
    ]
    with pytest.raises(UnusableSubmission, match=r"build/fifo: not a regular file"):
        walk(root)  # not skipped: the FIFO is found, never opened


def test_caps_are_checked_before_a_byte_is_read(tmp_path: Path) -> None:
    root = _folder(tmp_path / "team")
    with open(root / "big.bin", "wb") as f:
        f.truncate(MAX_FILE_BYTES + 1)
    with pytest.raises(UnusableSubmission, match=r"big.bin: \d+ bytes; a file is at most"):
        walk(root)
    with pytest.raises(UnusableSubmission, match=r"the files of the folder are over 20 bytes"):
        walk(_folder(tmp_path / "other"), max_total_bytes=20)
    with pytest.raises(UnusableSubmission, match=r"more than 1 files"):
        walk(_folder(tmp_path / "third"), max_files=1)


def test_links_are_kept_as_text_inside_and_refused_outside(tmp_path: Path) -> None:
    root = _folder(tmp_path / "team")
    (root / "alias.cpp").symlink_to("src/main.cpp")
    (root / "src_link").symlink_to("src")  # a link to a folder: not walked into
    found = {e.rel: e.link for e in walk(root)}
    assert found[b"alias.cpp"] == b"src/main.cpp" and found[b"src_link"] == b"src"
    (root / "out").symlink_to(tmp_path)
    with pytest.raises(UnusableSubmission, match=r"out: a link leaving the folder"):
        walk(root)


def test_stream_reads_the_file_the_walk_saw(tmp_path: Path) -> None:
    root = _folder(tmp_path / "team")
    entries = walk(root)
    chunks: list[bytes] = []
    stream(entries[0], chunks.append)
    assert b"".join(chunks) == b"project(x)\n"
    (root / "CMakeLists.txt").write_text("project(longer)\n", encoding="utf-8")
    with pytest.raises(UnusableSubmission, match=r"CMakeLists.txt: changed while it was read"):
        stream(entries[0], chunks.append)


def test_a_linked_team_is_told_in_one_line_what_to_do() -> None:
    assert linked(["team_x"]) == (
        "team_x is a link: usar reads only real folders, never through a link; copy it in its "
        "place (cp -rL) and grade again"
    )
    many = linked([f"t{i}" for i in range(6)])
    assert many.startswith("t0, t1, t2, t3 and 2 more are links:") and "copy each" in many


@pytest.mark.parametrize(
    "target",
    ["/opt/ros/noetic/share/catkin/cmake/toplevel.cmake",
     "/opt/ros/melodic/share/catkin/cmake/toplevel.cmake",
     "/usr/share/catkin/cmake/toplevel.cmake"],
)  # fmt: skip
def test_catkins_own_link_is_left_out_and_said(tmp_path: Path, target: str) -> None:
    """A committed ``catkin_make`` workspace keeps ``src/CMakeLists.txt`` -> catkin's
    ``toplevel.cmake``: catkin's, not the team's; never followed, left out (issue 51)."""
    root = _folder(tmp_path / "ws")
    (root / "src" / "CMakeLists.txt").symlink_to(target)
    said: list[str] = []
    assert [e.rel for e in walk(root, left_out=said)] == [b"CMakeLists.txt", b"src/main.cpp"]
    assert said == ["src/CMakeLists.txt: catkin's link out of the workspace, left out"]


@pytest.mark.parametrize(
    ("name", "target"),
    [("CMakeLists.txt", "/etc/passwd"),  # catkin's name, another target
     ("toplevel.cmake", "/opt/ros/noetic/share/catkin/cmake/toplevel.cmake"),  # another name
     ("CMakeLists.txt", "/opt/ros/noetic/share/catkin/cmake/toplevel.cmake/../../../x"),
     ("CMakeLists.txt", "../../../../opt/ros/noetic/share/catkin/cmake/toplevel.cmake")],
)  # fmt: skip
def test_other_links_out_keep_their_verdict(tmp_path: Path, name: str, target: str) -> None:
    root = _folder(tmp_path / "ws")
    (root / "src" / name).symlink_to(target)
    with pytest.raises(UnusableSubmission, match=rf"src/{name}: a link leaving the folder"):
        walk(root)
