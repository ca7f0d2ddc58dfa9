"""cli/__main__: ``python -m usar_replay.cli`` is the ``usar`` command, its exit code included."""

from __future__ import annotations

from pathlib import Path

from clitools import usar


def test_the_exit_code_of_main_is_the_processes(tmp_path: Path) -> None:
    assert usar("--help").returncode == 0
    missing = usar("info", str(tmp_path / "missing.mcap"))
    assert missing.returncode == 2 and missing.stderr.startswith("usar: error: ")
    empty = tmp_path / "empty.mcap"
    empty.write_bytes(b"")
    assert usar("info", str(empty)).returncode == 3
