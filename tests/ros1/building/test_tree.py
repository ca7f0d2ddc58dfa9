"""ros1/tree: a built workspace checked, frozen, listed and verified, on real files."""

from __future__ import annotations

import hashlib
import os
import socket
import stat
from pathlib import Path

import pytest

from usar_replay.ros1.building import tree


def _workspace(root: Path) -> Path:
    (root / "devel" / "lib").mkdir(parents=True)
    (root / "devel" / "setup.sh").write_text("export A=1\n", encoding="utf-8")
    (root / "devel" / "lib" / "node").write_bytes(b"\x7fELF")
    (root / "devel" / "lib" / "node").chmod(0o4755)  # set-uid, as a build might leave it
    (root / "devel" / "env.sh").symlink_to("setup.sh")  # a link inside: fine
    return root


def test_a_plain_workspace_passes_the_check(tmp_path: Path) -> None:
    tree.check(_workspace(tmp_path / "ws"))


def test_a_link_out_of_the_workspace_is_refused(tmp_path: Path) -> None:
    ws = _workspace(tmp_path / "ws")
    (ws / "devel" / "passwd").symlink_to("/etc/passwd")
    with pytest.raises(tree.TreeRefused, match=r"leaves its workspace: devel/passwd -> /etc"):
        tree.check(ws)
    (ws / "devel" / "passwd").unlink()
    (ws / "devel" / "up").symlink_to("../..")  # relative, but out all the same
    with pytest.raises(tree.TreeRefused, match=r"devel/up -> \.\./\.\."):
        tree.check(ws)


def test_special_files_are_refused(tmp_path: Path) -> None:
    ws = _workspace(tmp_path / "ws")
    os.mkfifo(ws / "devel" / "pipe")
    with pytest.raises(tree.TreeRefused, match="left a FIFO in its workspace: devel/pipe"):
        tree.check(ws)
    (ws / "devel" / "pipe").unlink()
    sock = socket.socket(socket.AF_UNIX)
    try:
        sock.bind(str(ws / "s"))
        with pytest.raises(tree.TreeRefused, match="left a socket in its workspace: s"):
            tree.check(ws)
    finally:
        sock.close()


def test_freeze_takes_write_and_set_id_bits_off(tmp_path: Path) -> None:
    ws = _workspace(tmp_path / "ws")
    tree.freeze(ws)
    mode = lambda p: stat.S_IMODE(os.lstat(p).st_mode)  # noqa: E731
    assert mode(ws / "devel" / "lib" / "node") == 0o555
    assert mode(ws / "devel" / "setup.sh") == 0o444
    assert mode(ws / "devel") == mode(ws / "devel" / "lib") == mode(ws) == 0o555
    assert os.readlink(ws / "devel" / "env.sh") == "setup.sh"


def test_the_manifest_lists_every_entry_and_verify_sees_a_change(tmp_path: Path) -> None:
    ws = _workspace(tmp_path / "ws")
    listed = tree.manifest(ws)
    sha = hashlib.sha256(b"export A=1\n").hexdigest()
    assert listed["devel/setup.sh"] == f"f 644 {sha}"
    assert listed["devel/env.sh"] == "l setup.sh"
    assert listed["devel/lib"] == "d 755"
    assert set(listed) == {
        ".",
        "devel",
        "devel/lib",
        "devel/lib/node",
        "devel/setup.sh",
        "devel/env.sh",
    }
    assert tree.verify(ws, listed) == ""
    (ws / "devel" / "setup.sh").write_text("export A=2\n", encoding="utf-8")
    assert tree.verify(ws, listed) == "devel/setup.sh changed since it was built"
    (ws / "devel" / "setup.sh").write_text("export A=1\n", encoding="utf-8")
    (ws / "devel" / "extra").write_bytes(b"")
    assert tree.verify(ws, listed) == "devel/extra changed since it was built"
    assert tree.verify(tmp_path / "gone", listed).startswith("cannot list it (")


def test_write_new_creates_read_only_and_never_overwrites(tmp_path: Path) -> None:
    path = tmp_path / "manifest.json"
    tree.write_new(path, "{}")
    assert path.read_text(encoding="utf-8") == "{}"
    assert stat.S_IMODE(path.stat().st_mode) == 0o444
    with pytest.raises(FileExistsError):
        tree.write_new(path, "again")
    (tmp_path / "link").symlink_to(tmp_path / "elsewhere")
    with pytest.raises(FileExistsError):
        tree.write_new(tmp_path / "link", "through a link")
    assert not (tmp_path / "elsewhere").exists()
