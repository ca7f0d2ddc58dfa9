"""``usar record`` stopped by ``--max-sim-time`` exits 1 and says why in one line: the log is
whole, but the run is not finished, and a script or a student must not read exit 1 as a crash
or take the log for a finished run."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import one_room

from usar_replay.cli.main import main
from usar_replay.log.run import open_run
from usar_replay.world.scenario_toml import save

STARTER = Path(__file__).resolve().parents[3] / "examples" / "starter_mission.py"


def test_max_sim_time_exits_1_and_says_why(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    world, out = tmp_path / "room.toml", tmp_path / "run.mcap"
    save(one_room(), world)
    args = ["record", "--scenario", str(world), "--mission", str(STARTER), "--out", str(out)]
    assert main([*args, "--max-sim-time", "2.5", "--quiet"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        "usar: exit 1: stopped by --max-sim-time 2.5 s before the mission said it was done"
    ]
    run = open_run(out)
    assert run.file_state == "complete" and run.outcome == "max_sim_time"
