"""ros1/building/build_folder: the build's workspace as a size- and inode-limited tmpfs, copied
to disk only when the build stayed within it. (A real build that fills it:
tests/redteam/test_build.py.)"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from usar_replay.ros1.building.build_folder import BuildFolder


@pytest.fixture(autouse=True)
def _root() -> None:
    if os.geteuid() != 0:
        pytest.skip("a tmpfs needs root (CI runs as root)")


def test_what_was_built_is_copied_to_disk_at_the_same_path(tmp_path: Path) -> None:
    ws = tmp_path / "ws"
    ws.mkdir()
    folder = BuildFolder(ws, 4, inodes=1000)
    assert folder.limited and os.path.ismount(ws)
    (ws / "devel").mkdir()
    (ws / "devel" / "setup.bash").write_text("# built\n")
    os.symlink("setup.bash", ws / "devel" / "link")
    assert not folder.full()
    folder.keep()
    assert not os.path.ismount(ws) and not folder.limited
    assert (ws / "devel" / "setup.bash").read_text() == "# built\n"
    assert os.readlink(ws / "devel" / "link") == "setup.bash"  # a link stays a link


def test_a_full_folder_is_said_and_nothing_is_kept(tmp_path: Path) -> None:
    ws = tmp_path / "ws"
    ws.mkdir()
    folder = BuildFolder(ws, 2, inodes=1000)
    with pytest.raises(OSError), (ws / "big").open("wb") as f:
        f.write(b"\0" * (3 << 20))  # past 2 MiB: the tmpfs refuses it
    assert folder.full()
    assert "2 MiB and 1,000 files: --build-folder" in folder.limit_words()
    folder.close()
    assert not os.path.ismount(ws) and list(ws.iterdir()) == []


def test_files_run_out_before_space(tmp_path: Path) -> None:
    ws = tmp_path / "ws"
    ws.mkdir()
    folder = BuildFolder(ws, 64, inodes=200)
    made = 0
    with pytest.raises(OSError):
        for made in range(400):
            (ws / str(made)).touch()
    assert 100 < made < 200 and folder.full()
    folder.close()


def test_no_size_is_a_plain_folder(tmp_path: Path) -> None:
    ws = tmp_path / "ws"
    ws.mkdir()
    folder = BuildFolder(ws, 0)
    assert not folder.limited and not os.path.ismount(ws) and not folder.full()
    (ws / "f").write_text("x")
    folder.keep()
    assert (ws / "f").read_text() == "x"
