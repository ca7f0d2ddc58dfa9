"""sandbox/run_folder: the run's folder is a size-limited tmpfs, and a full one is noticed."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from usar_replay.sandbox.run_folder import RunFolder, unmount_under


def test_a_run_folder_has_a_total_size_and_says_when_it_is_full() -> None:
    folder = RunFolder("usar-test-", 2)
    try:
        if not folder.limited:
            pytest.skip("no tmpfs can be mounted here (not root)")
        assert not folder.full()
        with pytest.raises(OSError), open(os.path.join(folder.path, "big"), "wb") as f:
            for _ in range(4):
                f.write(b"x" * (1 << 20))
        assert folder.full()
    finally:
        folder.close()
    assert not os.path.exists(folder.path)


def test_an_unlimited_folder_is_plain_and_never_full() -> None:
    folder = RunFolder("usar-test-", 0)
    try:
        assert not folder.limited and not folder.full()
        (open(os.path.join(folder.path, "kept"), "w")).close()
    finally:
        folder.close(keep=True)
    assert os.path.exists(os.path.join(folder.path, "kept"))
    folder.close()
    assert not os.path.exists(folder.path)


def test_folders_a_killed_run_left_mounted_are_unmounted_deepest_first(tmp_path: Path) -> None:
    """What the batch does once a run killed at its wall limit is gone: its folder's tmpfs,
    never closed, is unmounted, and the work folder can be removed (a name with a space, as
    /proc/self/mountinfo escapes it)."""
    import shutil
    import tempfile

    work = tmp_path / "team a" / ".work"
    work.mkdir(parents=True)
    before = tempfile.tempdir
    tempfile.tempdir = str(work)
    try:
        outer = RunFolder("usar-mission-", 2)
        if not outer.limited:
            pytest.skip("no tmpfs can be mounted here (not root)")
        tempfile.tempdir = outer.path
        inner = RunFolder("usar-ros1-", 2)  # a mount inside the first
    finally:
        tempfile.tempdir = before
    assert inner.limited and os.path.ismount(inner.path) and os.path.ismount(outer.path)
    assert unmount_under(str(tmp_path / "elsewhere")) == []  # nothing of another folder
    gone = unmount_under(str(work))
    assert sorted(gone) == sorted([outer.path, inner.path])
    assert not os.path.ismount(outer.path)
    shutil.rmtree(work)
    assert not work.exists()
