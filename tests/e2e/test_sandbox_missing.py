"""Without bubblewrap: `usar batch` refuses to grade untrusted code (exit 2, one line saying how to
get it or to pass --no-sandbox); `usar record` runs the mission unsandboxed after a one-line
warning. bwrap is taken away by running usar with an empty PATH (it is looked up on PATH)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from conftest import one_room

from usar_replay.world.scenario_toml import to_toml

ROOT = Path(__file__).resolve().parents[2]
MISSION = "from usar_replay.api import Node\n\n\ndef main() -> None:\n    Node('idle')\n"


def _usar(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k != "USAR_SANDBOX"}
    env.update(PATH="", PYTHONPATH=str(ROOT))
    return subprocess.run(
        [sys.executable, "-m", "usar_replay.cli", *args],
        cwd=cwd, env=env, capture_output=True, text=True, timeout=600, check=False,
    )  # fmt: skip


def test_batch_refuses_without_bwrap(tmp_path: Path) -> None:
    subs = tmp_path / "subs"
    subs.mkdir()
    (subs / "team.py").write_text(MISSION, encoding="utf-8")
    (tmp_path / "room.toml").write_text(to_toml(one_room()), encoding="utf-8")
    done = _usar("batch", "subs", "--scenario", "room.toml", "-o", "out", cwd=tmp_path)
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("usar: error: bubblewrap (bwrap) is not"), lines
    assert "apt-get install bubblewrap" in lines[0] and "--no-sandbox" in lines[0]
    assert not (tmp_path / "out" / "team").exists()  # nothing was run


def test_record_warns_and_runs_without_bwrap(tmp_path: Path) -> None:
    (tmp_path / "m.py").write_text(MISSION, encoding="utf-8")
    (tmp_path / "room.toml").write_text(to_toml(one_room()), encoding="utf-8")
    done = _usar(
        "record", "--scenario", "room.toml", "--mission", "m.py", "--max-sim-time", "0.5",
        "--out", "run.mcap", "--quiet", cwd=tmp_path,
    )  # fmt: skip
    assert done.returncode == 1, done.stderr  # recorded; the idle mission fails the rubric
    warnings = [line for line in done.stderr.splitlines() if line.startswith("usar: warning")]
    assert len(warnings) == 1 and "apt-get install bubblewrap" in warnings[0], done.stderr
    assert (tmp_path / "run.mcap").exists()
