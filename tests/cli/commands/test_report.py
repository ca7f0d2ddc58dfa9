"""`usar report` (cli/commands/report): pages written or refused before any work, a bad file
among good ones, exit codes. The pages themselves: tests/grading/test_htmlreport.py."""

from __future__ import annotations

from pathlib import Path

import pytest
from clitools import one_error_line, usar

from usar_replay.cli.main import main
from usar_replay.pipeline.record import RecordResult


def test_report_refuses_existing_pages_and_lists_a_bad_file(
    room_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    out = tmp_path / "pages"
    out.mkdir()
    (out / "index.html").write_text("keep")
    one_error_line(usar("report", str(room_log[0]), "-o", str(out)), 2, "--overwrite")
    assert (out / "index.html").read_text() == "keep"
    bad = tmp_path / "bad.mcap"
    bad.write_text("not a log")
    run = usar("report", str(room_log[0]), str(bad), "-o", str(out), "--overwrite")
    assert run.returncode == 3 and "Traceback" not in run.stderr
    index = (out / "index.html").read_text(encoding="utf-8")
    assert "href='room.html'" in index and "bad.html" not in index and "ERROR" in index


def test_report_prints_each_page_and_the_index(
    room_log: tuple[Path, RecordResult], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "pages"
    assert main(["report", str(room_log[0]), "-o", str(out)]) == 0
    assert capsys.readouterr().out.splitlines() == [
        f"wrote {out / 'room.html'}",
        f"wrote {out / 'index.html'} (1 recordings)",
    ]
    empty = tmp_path / "empty"
    empty.mkdir()
    assert main(["report", str(empty), "-o", str(out)]) == 2
    assert "no .mcap files in this folder" in capsys.readouterr().err
