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
