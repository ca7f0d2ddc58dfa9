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
from usar_replay.pipeline.record import record
from usar_replay.process.mission_process import MissionLimits
from usar_replay.sandbox.kernel_sandbox import bwrap_available

ROOT = Path(__file__).resolve().parents[2]
_OK, _WHY = bwrap_available()
needs_kernel_sandbox = pytest.mark.skipif(not _OK, reason=f"no kernel sandbox here: {_WHY}")

RUN = RunSettings(record=dataclasses.replace(RunSettings().record, max_sim_time_s=20.0))

# --- point 5: a mission that never reads its socket -------------------------------------------

DEAF = """
import struct, sys
from multiprocessing.connection import Connection

from usar_replay.api import Node
from usar_replay.process.protocol import ready_frame


def main() -> None:
    Node("deaf")
    conn = Connection(int(sys.argv[1]))
    conn.send_bytes(ready_frame())  # READY, then well-formed empty outputs forever, never reading
    empty = b"O" + struct.pack("<qI", 0, 0) + b"\\x00"
    for _ in range(1_000_000):
        conn.send_bytes(empty)
"""


@needs_kernel_sandbox
def test_a_mission_that_stops_reading_is_hung_within_the_tick_timeout(tmp_path: Path) -> None:
    mission = tmp_path / "deaf.py"
    mission.write_text(DEAF, encoding="utf-8")
    out = tmp_path / "deaf.mcap"
    result = record(
        one_room(), out, RUN, mission=str(mission),
        limits=MissionLimits(kernel_sandbox="required", tick_timeout_s=1.0),
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

NOISE = bytes(range(256)) * 2048  # 512 KiB a message, 8 a tick: 4 MiB per tick


class Flood(Node):
    def __init__(self) -> None:
        super().__init__("flood")
        self.pubs = [self.create_publisher(CompressedImage, f"/noise{i}") for i in range(8)]
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
    lim = MissionLimits(kernel_sandbox="required" if _OK else "off", **limits)  # type: ignore[arg-type]
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


# --- point 7: grading is bounded, and SIGTERM stops it -----------------------------------------

GRADE_BOMB = """
from usar_replay.api import Header, Node, Transform, TransformBroadcaster, TransformStamped, Vector3


class Bomb(Node):
    def __init__(self) -> None:
        super().__init__("bomb")
        self.tf = TransformBroadcaster(self)
        self.create_timer(0.1, self.on_timer)

    def on_timer(self) -> None:
        head = Header(stamp=self.get_clock().now().to_msg(), frame_id="explorer_tf/camera_link")
        for k in range(10):  # at the caps: 1,000 distinct marker frames a message, 10 a tick
            self.tf.sendTransform([
                TransformStamped(header=head, child_frame_id="marker_frame", transform=Transform(
                    translation=Vector3(x=1.0 + k + i * 1e-3)))
                for i in range(1000)
            ])


def main() -> None:
    Bomb()
"""


def test_sigterm_stops_grading_as_the_wall_limit() -> None:
    import signal

    from usar_replay.batch.run_one import GradeStopped, grading_deadline

    with pytest.raises(GradeStopped) as stopped, grading_deadline(60.0):
        os.kill(os.getpid(), signal.SIGTERM)  # the engine's wall limit, while grading
        signal.sigtimedwait([], 0)  # a signal is handled at the next bytecode
    assert stopped.value.outcome == "wall_limit"
    assert signal.getsignal(signal.SIGTERM) == signal.SIG_IGN  # files are written after it


# --- every point in one batch: each attacker its verdict, the honest grades unchanged -----------


@needs_kernel_sandbox
def test_a_class_of_runtime_attackers_gets_verdicts_and_honest_grades_do_not_move(
    tmp_path: Path,
) -> None:
    import io
    import json
    import sys

    from usar_replay.cli import main as cli
    from usar_replay.world.scenario_toml import to_toml

    subs, out = tmp_path / "subs", tmp_path / "out"
    subs.mkdir()
    room = tmp_path / "room.toml"
    room.write_text(to_toml(one_room()), encoding="utf-8")
    honest = (ROOT / "examples" / "minimal_mission.py").read_text(encoding="utf-8")
    (subs / "honest_a.py").write_text(honest, encoding="utf-8")
    (subs / "honest_z.py").write_text(honest, encoding="utf-8")
    for team, source in (("deaf", DEAF), ("flood", FLOOD), ("bomb", GRADE_BOMB)):
        (subs / f"{team}.py").write_text(source, encoding="utf-8")
    reasons = _hostile_folders(subs)
    buf, old = io.StringIO(), sys.stdout
    sys.stdout = buf
    try:
        code = cli.main(
            ["batch", str(subs), "--scenario", str(room), "-o", str(out), "--max-sim-time", "3",
             "--tick-timeout", "5", "--max-log-mib", "48", "--grade-limit", "0.25", "--jobs", "2",
             "--quiet"]
        )  # fmt: skip
        # The grade limit sits far from both sides (measured on a 2-core machine): the honest
        # 3 s log grades in about 2 ms, the bomb's in about 2.5 s, so neither side is a race.
    finally:
        sys.stdout = old
    assert code == 0, buf.getvalue()  # every team has its verdict: none made the batch fail

    def grade(team: str) -> dict[str, object]:
        data: dict[str, object] = json.loads((out / team / "room.grade.json").read_text())
        return data

    a, z = grade("honest_a"), grade("honest_z")
    assert a["outcome"] == z["outcome"] == "max_sim_time"
    mine = ("team", "log_sha256")
    assert {k: v for k, v in a.items() if k not in mine} == {
        k: v for k, v in z.items() if k not in mine
    }
    assert grade("deaf")["outcome"] == "hung"
    assert "did not read its input" in str(grade("deaf")["outcome_reason"])
    assert grade("flood")["outcome"] == "refused"
    assert "budget of 48 MiB" in str(grade("flood")["outcome_reason"])
    bomb = grade("bomb")
    assert bomb["outcome"] == "grade_limit" and bomb["points"] == 0.0, bomb["outcome_reason"]
    summary = (out / "summary.csv").read_text(encoding="utf-8")
    for team, reason in reasons.items():
        assert not (out / team / "room.grade.json").exists()  # nothing of it was run
        line = next(x for x in summary.splitlines() if x.startswith(team + ","))
        assert "unusable submission: " + reason in line, line


@pytest.mark.parametrize(
    "args",
    [
        ("record", "--max-log-mib", "-1"),
        ("batch", "subs", "-o", "out", "--max-log-mib", "-1"),
        ("batch", "subs", "-o", "out", "--grade-limit", "0"),
    ],
)
def test_a_bad_budget_or_grade_limit_is_one_line(tmp_path: Path, args: tuple[str, ...]) -> None:
    from clitools import one_error_line, usar

    (tmp_path / "subs").mkdir()
    one_error_line(usar(*args, cwd=tmp_path), 2, args[-2])
