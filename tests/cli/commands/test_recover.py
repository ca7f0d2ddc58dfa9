"""`usar recover` (cli/commands/recover): a cut log's readable messages into a whole log, said
in lines that fit 100 columns; on a log written by usar's writer and cut as a kill leaves it."""

from __future__ import annotations

from pathlib import Path

import pytest

from usar_replay.cli.main import main
from usar_replay.core import contract, msgs
from usar_replay.log import bag

S = 1_000_000_000


def _cut(tmp_path: Path) -> Path:
    whole = tmp_path / "whole.mcap"
    with bag.BagWriter(whole, chunk_size=1024) as w:
        for i in range(300):
            w.write(contract.ROSOUT, msgs.Log(name="explorer", msg=f"line {i}"), S + i * S // 10)
    part = tmp_path / "run.mcap.part"
    data = whole.read_bytes()
    part.write_bytes(data[: len(data) // 2])
    return part


def test_recover_says_what_it_wrote(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    part = _cut(tmp_path)
    assert main(["recover", str(part)]) == 0
    out = capsys.readouterr().out
    lines = out.splitlines()
    assert lines[0].startswith("recovered ") and "marked interrupted" in out
    assert all(len(line) <= 100 for line in lines)
    flat = " ".join(out.split())
    assert f"from {part}" in flat and f"into {part.with_name('run.mcap')}" in flat
    assert "what was damaged:" in flat
    assert bag.BagReader(part.with_name("run.mcap")).status == "interrupted"


def test_an_existing_output_and_a_whole_log_are_usage_errors(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    part = _cut(tmp_path)
    taken = tmp_path / "taken.mcap"
    taken.write_bytes(b"mine")
    assert main(["recover", str(part), "-o", str(taken)]) == 2
    assert "exists; pass --overwrite" in capsys.readouterr().err
    assert main(["recover", str(part), "-o", str(taken), "--overwrite"]) == 0
    capsys.readouterr()
    assert main(["recover", str(tmp_path / "whole.mcap")]) == 2
    assert "the log is whole; there is nothing to recover" in capsys.readouterr().err
