"""core/outfiles: outputs never over an input, never over a file without --overwrite, never
half-written at the final name; on real files."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from usar_replay.core.errors import UsageError
from usar_replay.core.outfiles import atomic_output, check_output, write_bytes, write_text


def test_check_output_refuses_an_input_a_folder_and_an_existing_file(tmp_path: Path) -> None:
    log = tmp_path / "run.mcap"
    log.write_bytes(b"log")
    with pytest.raises(UsageError, match=r"--json .*run.mcap: is an input of this command"):
        check_output(log, inputs=[log], option="--json")
    (tmp_path / "alias.mcap").symlink_to(log)
    with pytest.raises(UsageError, match="is an input"):
        check_output(tmp_path / "alias.mcap", overwrite=True, inputs=[log])
    with pytest.raises(UsageError, match="is a directory; give a file name"):
        check_output(tmp_path)
    with pytest.raises(UsageError, match="exists; pass --overwrite to replace it"):
        check_output(log)
    assert check_output(log, overwrite=True) == log
    with pytest.raises(UsageError, match=r"run.mcap is not a directory"):
        check_output(log / "x.json")
    assert check_output(tmp_path / "new.json") == tmp_path / "new.json"


def test_write_text_and_bytes_land_whole_and_make_folders(tmp_path: Path) -> None:
    out = write_text(tmp_path / "sub" / "grade.json", '{"ok": true}\n')
    assert out.read_text(encoding="utf-8") == '{"ok": true}\n'
    write_bytes(tmp_path / "a.bin", b"\0\1", overwrite=False)
    assert (tmp_path / "a.bin").read_bytes() == b"\0\1"
    write_text(tmp_path / "a.bin", "new", overwrite=True)
    assert (tmp_path / "a.bin").read_text(encoding="utf-8") == "new"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.bin", "sub"]  # no temporary left


def test_a_failure_while_writing_leaves_the_old_file(tmp_path: Path) -> None:
    path = tmp_path / "report.html"
    path.write_text("old", encoding="utf-8")
    with pytest.raises(RuntimeError), atomic_output(path, overwrite=True) as f:
        f.write("half")
        raise RuntimeError("cut off")
    assert path.read_text(encoding="utf-8") == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["report.html"]


def test_a_file_that_appears_while_writing_is_kept(tmp_path: Path) -> None:
    path = tmp_path / "out.csv"
    with (
        pytest.raises(UsageError, match="appeared while this command ran"),
        atomic_output(path) as f,
    ):
        f.write("mine")
        path.write_text("theirs", encoding="utf-8")
    assert path.read_text(encoding="utf-8") == "theirs"


def test_a_link_at_the_output_is_replaced_not_written_through(tmp_path: Path) -> None:
    target = tmp_path / "elsewhere.txt"
    target.write_text("keep", encoding="utf-8")
    path = tmp_path / "out.txt"
    path.symlink_to(target)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.symlink_to(target)  # planted at the temporary name too
    write_text(path, "new", overwrite=True)
    assert target.read_text(encoding="utf-8") == "keep"
    assert not path.is_symlink() and path.read_text(encoding="utf-8") == "new"


def test_an_unwritable_folder_is_one_line(tmp_path: Path) -> None:
    with pytest.raises(UsageError, match=r"cannot write"):
        write_text("/proc/usar-test-output.txt", "x")
