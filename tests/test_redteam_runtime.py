"""Red team: runtime denial of service (issue #26, points 5 to 8) ends as the team's verdict.

Each attack is a tiny mission file (or team folder) written here, run through the real recorder,
grader or batch: a mission that stops reading its socket (point 5), one that floods the log
(point 6), one that plants a grade bomb (point 7) and team folders with a FIFO, a link to
``/dev/zero`` and a huge sparse file (point 8). Each must end as a verdict for the attacker
alone, in a closed, gradeable log, while an honest team's grade does not move.

Needs bubblewrap for the recorder tests (as tests/test_redteam_sandbox.py); the batch-folder
tests run anywhere.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest
from conftest import one_room

from usar_replay.core.settings import RunSettings
from usar_replay.log.run import open_run
from usar_replay.node.jail import bwrap_available
from usar_replay.node.worker import MissionLimits
from usar_replay.pipeline.record import record

ROOT = Path(__file__).resolve().parents[1]
_OK, _WHY = bwrap_available()
needs_jail = pytest.mark.skipif(not _OK, reason=f"no kernel sandbox here: {_WHY}")

RUN = RunSettings(record=dataclasses.replace(RunSettings().record, max_sim_time_s=20.0))

# --- point 5: a mission that never reads its socket -------------------------------------------

DEAF = """
import struct, sys
from multiprocessing.connection import Connection

from usar_replay.api import Node


def main() -> None:
    Node("deaf")
    conn = Connection(int(sys.argv[1]))
    conn.send_bytes(b"R")  # READY, then well-formed empty outputs forever, never reading
    empty = b"O" + struct.pack("<qI", 0, 0) + b"\\x00"
    for _ in range(1_000_000):
        conn.send_bytes(empty)
"""


@needs_jail
def test_a_mission_that_stops_reading_is_hung_within_the_tick_timeout(tmp_path: Path) -> None:
    mission = tmp_path / "deaf.py"
    mission.write_text(DEAF, encoding="utf-8")
    out = tmp_path / "deaf.mcap"
    result = record(
        one_room(), out, RUN, mission=str(mission),
        limits=MissionLimits(jail="required", tick_timeout_s=1.0),
    )  # fmt: skip
    assert result.outcome == "hung", result.outcome_reason
    assert "did not read its input within 1 s" in result.outcome_reason
    run = open_run(out)
    assert run.file_state == "complete" and run.outcome == "hung"
