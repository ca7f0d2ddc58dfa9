"""The `usar` command as a user runs it: help, a missing log, exit codes."""

from __future__ import annotations

from pathlib import Path

import pytest
from clitools import usar


def test_help_lists_every_command() -> None:
    out = usar("--help")
    assert out.returncode == 0
    for name in ("record", "replay", "grade", "view", "info"):
        assert name in out.stdout


@pytest.mark.parametrize("command", ["replay", "grade"])
def test_missing_log_is_one_line_exit_2(command: str, tmp_path: Path) -> None:
    missing = tmp_path / "x.mcap"
    out = usar(command, str(missing))
    assert out.returncode == 2
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and "no such file" in lines[0] and str(missing) in lines[0]
    assert "Traceback" not in out.stderr


def test_whatever_a_command_prints_on_stdout_is_escaped(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """The last line of defence (#33 point 9): a path from a log's strings to stdout that no
    module escaped (here: ``usar info``'s report, made raw on purpose) still reaches the
    terminal escaped, as ``grade``'s table and ``replay``'s report do."""
    from usar_replay.cli.main import main
    from usar_replay.log import info

    log = tmp_path / "x.mcap"
    log.write_bytes(b"\x89MCAP0\r\n")  # opened, then described by the raw stand-in
    monkeypatch.setattr(info, "open_checked", lambda path, quick=False: object())
    monkeypatch.setattr(info, "describe", lambda run, quick=False: "Topics: /a\x1b[2J\x07\x9b")
    monkeypatch.setattr(info, "is_whole", lambda run: True)
    assert main(["info", str(log)]) == 0
    out = capsys.readouterr()
    assert out.out == "Topics: /a\\x1b[2J\\x07\\x9b\n"
