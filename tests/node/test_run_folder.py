"""node/run_folder: the run's folder is a size-limited tmpfs, and a full one is noticed."""

from __future__ import annotations

import os

import pytest

from usar_replay.node.run_folder import RunFolder


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
