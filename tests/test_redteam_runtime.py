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
import os
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


# --- point 8: a team folder usar must not read --------------------------------------------------


def _hostile_folders(subs: Path) -> dict[str, str]:
    """Team folders with a mission and one thing a plain read would hang or die on; returns
    each team's expected reason."""
    minimal = (ROOT / "examples" / "minimal_mission.py").read_text(encoding="utf-8")
    reasons = {}
    for team in ("fifo", "zero", "sparse", "linkout"):
        folder = subs / team
        folder.mkdir()
        (folder / "mission.py").write_text(minimal, encoding="utf-8")
    os.mkfifo(subs / "fifo" / "weights.bin")
    reasons["fifo"] = "weights.bin: not a regular file"
    (subs / "zero" / "data.bin").symlink_to("/dev/zero")
    reasons["zero"] = "data.bin: a link leaving the team's folder"
    with open(subs / "sparse" / "big.bin", "wb") as f:
        f.truncate(30 * 1024**3)  # 30 GB, no block of it written
    reasons["sparse"] = "big.bin: 32212254720 bytes; a file is at most"
    (subs / "linkout" / "helpers.py").symlink_to("/etc/passwd")
    reasons["linkout"] = "helpers.py: a link leaving the team's folder"
    return reasons


def test_unusable_team_folders_are_that_teams_verdict(tmp_path: Path) -> None:
    from usar_replay.batch.plan import discover

    subs = tmp_path / "subs"
    subs.mkdir()
    reasons = _hostile_folders(subs)
    (subs / "honest").mkdir()
    (subs / "honest" / "mission.py").write_bytes(
        (ROOT / "examples" / "minimal_mission.py").read_bytes()
    )
    (subs / "honest" / "inner.py").symlink_to("mission.py")  # a link inside is fine
    found = {s.team: s for s in discover(subs)}
    assert set(found) == {*reasons, "honest"}
    for team, reason in reasons.items():
        assert found[team].problem_outcome == "bad_submission", team
        assert found[team].problem.startswith("unusable submission: " + reason), found[team]
        assert found[team].target == ""
    assert found["honest"].problem == "" and found["honest"].target.endswith("mission.py")


# --- point 6: a mission that floods the log ----------------------------------------------------

FLOOD = """
from usar_replay.api import CompressedImage, Node

NOISE = bytes(range(256)) * 2048  # 512 KiB a message, 4 a tick: 2 MiB per tick


class Flood(Node):
    def __init__(self) -> None:
        super().__init__("flood")
        self.pubs = [self.create_publisher(CompressedImage, f"/noise{i}") for i in range(4)]
        self.create_timer(0.1, self.on_timer)

    def on_timer(self) -> None:
        for pub in self.pubs:
            pub.publish(CompressedImage(format="raw", data=NOISE))


def main() -> None:
    Flood()
"""

TF_BOMB = """
from usar_replay.api import Node, TransformBroadcaster, TransformStamped, Header


class Bomb(Node):
    def __init__(self) -> None:
        super().__init__("bomb")
        self.tf = TransformBroadcaster(self)
        self.create_timer(0.1, self.on_timer)

    def on_timer(self) -> None:
        stamp = self.get_clock().now().to_msg()
        self.tf.sendTransform([
            TransformStamped(header=Header(stamp=stamp, frame_id="explorer_tf/camera_link"),
                             child_frame_id="marker_frame")
            for _ in range(5000)
        ])


def main() -> None:
    Bomb()
"""


def _record_attack(tmp_path: Path, source: str, **limits: object) -> tuple[Path, object]:
    mission = tmp_path / "attack.py"
    mission.write_text(source, encoding="utf-8")
    out = tmp_path / "attack.mcap"
    lim = MissionLimits(jail="required" if _OK else "off", **limits)  # type: ignore[arg-type]
    return out, record(one_room(), out, RUN, mission=str(mission), limits=lim)


def test_a_log_over_its_byte_budget_is_refused_closed_and_gradeable(tmp_path: Path) -> None:
    from usar_replay.grading.grade import grade_file

    out, result = _record_attack(tmp_path, FLOOD, max_log_mib=4)
    assert result.outcome == "refused", result.outcome_reason  # type: ignore[attr-defined]
    assert "passed its budget of 4 MiB" in result.outcome_reason  # type: ignore[attr-defined]
    run = open_run(out)
    assert run.file_state == "complete" and run.outcome == "refused"
    assert out.stat().st_size < 5 * 1024 * 1024  # the tick that crossed it was not written
    report = grade_file(out)
    assert report.checks  # graded: a report with its lines, not an error


def test_a_tf_message_with_thousands_of_transforms_is_refused(tmp_path: Path) -> None:
    out, result = _record_attack(tmp_path, TF_BOMB)
    assert result.outcome == "refused", result.outcome_reason  # type: ignore[attr-defined]
    assert "5000 transforms" in result.outcome_reason  # type: ignore[attr-defined]
    assert open_run(out).file_state == "complete"


def test_the_recorder_refuses_too_many_transforms_whatever_the_mission_process_says() -> None:
    from usar_replay.core import cdr, msgs
    from usar_replay.node.boundary_check import BoundaryCheck, OutputRefused
    from usar_replay.node.executor import PublishPolicy

    check = BoundaryCheck(PublishPolicy(sim_topics=(), sim_frames=()))
    one = msgs.TransformStamped(
        header=msgs.Header(frame_id="explorer_tf/camera_link"), child_frame_id="marker_frame"
    )
    tf = msgs.TFMessage.__msgtype__
    ok = cdr.encode(msgs.TFMessage(transforms=(one,) * 1000))
    assert len(check.check([("/tf", tf, ok)] * 10)) == 10  # 1,000 a message, 10,000 a tick
    with pytest.raises(OutputRefused, match="1001 transforms"):
        check.check([("/tf", tf, cdr.encode(msgs.TFMessage(transforms=(one,) * 1001)))])
    with pytest.raises(OutputRefused, match="11000 transforms in one tick"):
        check.check([("/tf", tf, ok)] * 11)
