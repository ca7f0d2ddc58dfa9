"""`usar grade` as a user runs it: sub-folders, one line per recording, outputs that never replace
an input or an existing file, an unreadable file in a parallel batch, Ctrl-C, a damaged log."""

from __future__ import annotations

import csv
import io
import os
import pty
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from clitools import default_signals, one_error_line, usar

from usar_replay.pipeline.record import RecordResult


def _batch(room_log: tuple[Path, RecordResult], root: Path, n: int) -> list[Path]:
    """``n`` links to the recorded log in nested sub-folders (cheap copies)."""
    paths = []
    for i in range(n):
        p = root / f"group{i % 3}" / f"student{i:02d}" / "run.mcap"
        p.parent.mkdir(parents=True, exist_ok=True)
        os.link(room_log[0], p)
        paths.append(p)
    return paths


def test_a_folder_is_searched_with_its_sub_folders(
    room_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    paths = _batch(room_log, tmp_path / "runs", 3)
    (tmp_path / "runs" / ".hidden").mkdir()
    os.link(room_log[0], tmp_path / "runs" / ".hidden" / "skip.mcap")
    out = subprocess.run(
        [sys.executable, "-m", "usar_replay.cli", "grade", "runs"], cwd=tmp_path,
        capture_output=True, text=True, check=False, env={**os.environ, "COLUMNS": "80"},
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert lines[0] == "Grade of 3 recordings:"
    expect = sorted(str(p.relative_to(tmp_path)) for p in paths)
    assert [line.split()[-1] for line in lines[1:4]] == expect
    assert all(line.startswith("PASS   60/60") for line in lines[1:4])
    assert lines[-1] == "3/3 recordings pass"
    assert max(len(line) for line in lines) <= 80
    assert "skip.mcap" not in out.stdout


@pytest.mark.parametrize("option", ["--json", "--csv", "--junit"])
def test_an_output_over_the_input_is_refused(
    room_log: tuple[Path, RecordResult], tmp_path: Path, option: str
) -> None:
    log = tmp_path / "a.mcap"
    log.write_bytes(room_log[0].read_bytes())
    before = log.read_bytes()
    one_error_line(usar("grade", str(log), option, str(log)), 2, "input")
    one_error_line(usar("grade", str(log), option, str(log), "--overwrite"), 2, "input")
    assert log.read_bytes() == before


def test_an_existing_output_needs_overwrite(
    room_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    out_json = tmp_path / "g.json"
    out_json.write_text("keep me")
    one_error_line(usar("grade", str(room_log[0]), "--json", str(out_json)), 2, "--overwrite")
    assert out_json.read_text() == "keep me"
    ok = usar("grade", str(room_log[0]), "--json", str(out_json), "--overwrite")
    assert ok.returncode == 0 and '"schema_version": 1' in out_json.read_text()
    assert [p.name for p in tmp_path.iterdir()] == ["g.json"]  # no temporary file left
    same = usar(
        "grade", str(room_log[0]), "--json", str(tmp_path / "x"), "--csv", str(tmp_path / "x")
    )
    one_error_line(same, 2, "also given to --json")


def _without_root_reads() -> list[str]:
    """A command prefix under which even root cannot read a chmod 000 file (root reads through
    CAP_DAC_OVERRIDE; ``setpriv`` drops it); empty for an ordinary user."""
    if os.geteuid() != 0:
        return []
    setpriv = shutil.which("setpriv")
    if setpriv is None:
        pytest.skip("root reads a chmod 000 file, and setpriv is not installed")
    caps = "-dac_override,-dac_read_search"
    return [setpriv, "--bounding-set", caps, "--inh-caps", caps, "--"]


def test_an_unreadable_file_is_one_entry_and_the_batch_goes_on(
    room_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    paths = _batch(room_log, tmp_path / "runs", 3)
    locked = tmp_path / "runs" / "locked.mcap"
    locked.write_bytes(b"x" * 100)
    locked.chmod(0)
    table = tmp_path / "g.csv"
    try:
        out = subprocess.run(
            [*_without_root_reads(), sys.executable, "-m", "usar_replay.cli", "grade",
             str(tmp_path / "runs"), "--jobs", "2", "--csv", str(table)],
            capture_output=True, text=True, check=False,
        )  # fmt: skip
    finally:
        locked.chmod(0o600)
    one_error_line(out, 2, str(locked), "permission denied")
    rows = list(csv.DictReader(io.StringIO(table.read_text())))
    assert len(rows) == len(paths) + 1
    bad = [r for r in rows if r["status"] == "error"]
    assert len(bad) == 1 and bad[0]["recording"] == str(locked)
    assert "ERROR" in out.stdout and "3/4 recordings pass" in out.stdout


def test_ctrl_c_during_a_parallel_batch_is_one_line_and_130(
    room_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    """Ctrl-C in a terminal reaches the whole process group, workers included: the progress bar
    on a pseudo-terminal tells when grading has begun."""
    _batch(room_log, tmp_path / "runs", 60)
    master, slave = pty.openpty()
    proc = subprocess.Popen(
        [sys.executable, "-m", "usar_replay.cli", "grade", str(tmp_path / "runs"), "--jobs", "2"],
        preexec_fn=default_signals,
        stdout=subprocess.PIPE, stderr=slave, start_new_session=True,
    )  # fmt: skip
    os.close(slave)
    seen = b""
    while b"/60" not in seen:  # rich's "N/60": at least one recording graded
        chunk = os.read(master, 4096)
        assert chunk, "the grader ended before showing progress"
        seen += chunk
    os.killpg(proc.pid, signal.SIGINT)
    proc.wait(timeout=300)  # workers finish the file in hand; generous for a loaded machine
    rest = b""
    try:
        while chunk := os.read(master, 4096):
            rest += chunk
    except OSError:  # the terminal closed with the process
        pass
    os.close(master)
    assert proc.stdout is not None
    proc.stdout.close()
    text = rest.decode(errors="replace")
    assert proc.returncode == 130, text
    assert "Traceback" not in text and "KeyboardInterrupt" not in text
    assert text.count("usar: interrupted") == 1


def test_a_damaged_log_is_exit_3_and_says_what(
    room_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    data = room_log[0].read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    out = usar("grade", str(cut))
    assert out.returncode == 3 and "Traceback" not in out.stderr
    assert "incomplete" in out.stderr and "read" in out.stderr and "messages" in out.stderr
