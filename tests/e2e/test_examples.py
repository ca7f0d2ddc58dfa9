"""The example missions: the starter runs and fails cleanly; each faulty mission (one student bug
of the course, examples/faulty/) fails exactly the rubric lines its bug should fail.

Bugs in detecting, broadcasting and storing are judged by replaying the faulty mission open loop
on the session's one-room recording (``room_log``): the robots move as the built-in mission drove
them, so the robot lines pass and only the lines the mission's own outputs decide can fail.
Bugs that change where the robots go are recorded closed loop on small worlds
(tests/example_worlds.py). Two of them need the two-marker corridor (about 100 s of sim time,
1.5-2.5 min of wall time each on 2 busy cores): those are marked slow.

Where the rubric does not catch a bug yet, the test says what it should fail and is marked
``xfail(strict=True)`` with the reason, next to a test that the bug really is in the outputs:
when the grader learns to catch it, the xfail turns into a failure and is removed.
"""

from __future__ import annotations

import dataclasses
import textwrap
from collections.abc import Sequence
from pathlib import Path

import pytest
from conftest import one_room
from example_worlds import CORRIDOR_SETTINGS, corridor, quick_room

from usar_replay.cli.main import main
from usar_replay.core import contract, msgs
from usar_replay.core.settings import RecordSettings, RunSettings
from usar_replay.grading.grade import GradeReport, grade_file
from usar_replay.grading.usar import GRADE_TOPICS, Grader
from usar_replay.log.run import open_run
from usar_replay.pipeline.record import RecordResult, record
from usar_replay.pipeline.replay import ReplayReport, replay
from usar_replay.world.scenario_toml import save

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
FAULTY = EXAMPLES / "faulty"

Message = tuple[str, msgs.Message | None, int]


def _failed(report: GradeReport) -> set[str]:
    return {c.id for c in report.checks if not c.passed}


def _expect_only_the_cmd_vel_lines_pass(report: GradeReport) -> None:
    """A run that ended at once: every line fails but the two ``cmd_vel_one_publisher`` lines;
    ``marker_0.detected`` is left out (it depends on whether the detector saw the marker
    3.2 m away before the end)."""
    passing = ("explorer.cmd_vel_one_publisher", "follower.cmd_vel_one_publisher")
    report = dataclasses.replace(
        report, checks=tuple(c for c in report.checks if c.id != "marker_0.detected")
    )
    _expect(report, [c.id for c in report.checks if c.id not in passing])


def _expect(report: GradeReport, failed: Sequence[str]) -> None:
    """Exactly these lines fail (with no points), every other line passes (full points)."""
    ids = {c.id for c in report.checks}
    assert set(failed) <= ids, "a line that is not there"
    assert _failed(report) == set(failed), [(c.id, c.measured) for c in report.checks]
    for c in report.checks:
        assert c.points == (0.0 if c.id in failed else c.max_points), c.id


def _replay(
    log: Path, mission: str, keep: Sequence[str] = ()
) -> tuple[ReplayReport, GradeReport, list[Message]]:
    """Replay ``mission`` open loop on ``log`` and grade its outputs (as `usar replay --grade`);
    also returns the replay's messages on ``keep`` (decoded)."""
    run = open_run(log)
    grader = Grader(run.require_scenario())
    kept: list[Message] = []

    def sink(topic: str, msg: msgs.Message | None, t: int) -> None:
        grader.feed(topic, msg, t)
        if topic in keep:
            kept.append((topic, msg, t))

    rep = replay(
        run, mission=str(FAULTY / mission), grade_sink=sink, grade_topics=(*GRADE_TOPICS, *keep)
    )
    assert rep.mission_failure is None, rep.mission_failure_detail
    assert rep.regression and not rep.same_code
    return rep, grader.report(f"{log} ({mission} replayed)"), kept


# --- the starter --------------------------------------------------------------------------------


def test_the_starter_runs_and_fails_the_rubric_cleanly(tmp_path: Path) -> None:
    settings = RunSettings(record=RecordSettings(max_sim_time_s=5.0))
    result = record(
        one_room(),
        tmp_path / "starter.mcap",
        settings,
        mission=str(EXAMPLES / "starter_mission.py"),
    )
    assert result.outcome == "max_sim_time", result.outcome_reason  # no crash: it just waits
    report = grade_file(tmp_path / "starter.mcap")
    assert report.log_complete
    # nothing drives the robots, so no cmd_vel conflicts; every other line fails (with no
    # broadcast at all, only_on_detection too: "nothing broadcast" earns no credit), except
    # marker_0.detected, which depends on whether the course's detector node sees the marker
    # 3.2 m away in the first 5 s (JPEG at 320x240: it does not; PNG: it does)
    assert report.check("marker_frame.only_on_detection").measured.startswith(
        "nothing broadcast"
    )
    _expect_only_the_cmd_vel_lines_pass(report)


# --- the first mission of docs/node-api.md --------------------------------------------------


def test_docs_show_the_first_mission_as_shipped() -> None:
    """docs/node-api.md prints examples/first_mission.py whole: the two cannot drift apart."""
    docs = (EXAMPLES.parent / "docs" / "node-api.md").read_text()
    assert (EXAMPLES / "first_mission.py").read_text().rstrip() + "\n```" in docs


def test_the_first_mission_is_graded_whatever_it_leaves_out(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """docs/node-api.md's 40-line first mission, recorded and graded as a student would: the
    explorer's lines pass, the follower's (it has none) fail, exit 1, never 3. Its constructor's
    log line reaches the log at the first tick; the record summary counts the marker as the
    rubric does, though it never publishes /explorer/marker_poses. Without its detector node
    it gets the same detections: the course's detector runs on usar's side."""
    world = tmp_path / "room.toml"
    save(quick_room(), world)  # the one-room world, the explorer starting near the target
    first = EXAMPLES / "first_mission.py"
    code_lines = [ln for ln in first.read_text().splitlines() if ln.strip()]
    assert len(code_lines) <= 45, "the first mission must stay short"
    out = tmp_path / "first.mcap"
    base = ["record", "--scenario", str(world), "--quiet"]
    assert main([*base, "--mission", str(first), "--out", str(out)]) == 0
    summary = capsys.readouterr().out
    assert "Markers found: 1/1 (as `usar grade` counts them)" in summary, summary
    assert "  marker 0: " in summary and " cm from the marker" in summary, summary
    run = open_run(out)
    assert contract.MARKER_POSES not in run.topics
    rosout = next(iter(run.messages([contract.ROSOUT])))
    assert isinstance(rosout.msg, msgs.Log) and rosout.msg.msg == "1 targets"
    assert rosout.log_time_ns == run.start_ns  # made in __init__, written at the first tick
    report = grade_file(out)
    _expect(report, ["follower.marker_0", "follower.home", "time_limit"])
    assert main(["grade", str(out)]) == 1

    # without its detector node: the same run, the course's detections (trusted, from "sim")
    blind = tmp_path / "no_detector.py"
    blind.write_text(first.read_text().replace("    ArucoDetect()\n", ""))
    out = tmp_path / "blind.mcap"
    main([*base, "--mission", str(blind), "--out", str(out), "--max-sim-time", "3"])
    assert open_run(out).reader.publishers(contract.FIDUCIALS) == {"sim"}
    capsys.readouterr()
    assert main(["grade", str(out)]) == 1
    graded = " ".join(capsys.readouterr().out.split())
    assert "no /fiducial_transforms in the log" not in graded
    # `usar replay --grade` too: the same outputs, the same graded (not refused) run
    assert main(["replay", "--grade", str(out)]) == 1
    replayed = " ".join(capsys.readouterr().out.split())
    assert "bit for bit" in replayed and "no /fiducial_transforms in the log" not in replayed


# --- detection / broadcast / storing bugs: replay on the one-room log --------------------------


def test_broadcast_with_the_wrong_parent(room_log: tuple[Path, RecordResult]) -> None:
    _, report, _ = _replay(room_log[0], "wrong_parent.py")
    _expect(report, ["marker_0.broadcast", "marker_frame.only_on_detection"])
    assert "1 with another parent" in report.check("marker_frame.only_on_detection").measured


def test_broadcast_on_frames_without_a_detection(room_log: tuple[Path, RecordResult]) -> None:
    _, report, _ = _replay(room_log[0], "broadcast_without_detection.py")
    _expect(report, ["marker_0.broadcast", "marker_frame.only_on_detection"])


def test_an_extra_identity_broadcast_stores_the_cameras_pose(
    room_log: tuple[Path, RecordResult],
) -> None:
    """The stored "marker" is where the camera was (team 001: their marker map equalled the
    lookup targets). Closed loop, the follower would also miss the marker; replayed, the
    follower lines are the recorded (correct) drive's."""
    _, report, kept = _replay(room_log[0], "identity_broadcast.py", [contract.MARKER_POSES])
    _expect(report, ["marker_0.broadcast"])
    stored = [m for _, m, _ in kept if isinstance(m, msgs.FiducialTransformArray)][-1]
    p = stored.transforms[0].transform.translation
    target = one_room().targets[0]
    assert abs(p.x - target[0]) < 0.25 and abs(p.y - target[1]) < 0.25  # at the lookup target


def test_stamped_now_and_looked_up_at_latest(room_log: tuple[Path, RecordResult]) -> None:
    """marker_frame stamped with the loop's "now" and looked up at Time() (latest): the
    stored pose lags by the turn of one loop period (about a centimetre at 0.1 rad/s, under the
    10 cm of marker_0.broadcast). Since the course's detector runs on usar's side (issue #21),
    its detection of a tick's frame is an input of that tick, logged before the mission's
    outputs: a broadcast stamped with the tick's time names a detected frame, and
    only_on_detection (which judges stamps) no longer tells it from the detection callback's
    (before, the mission's own detector published after the timer, and the line failed)."""
    _, report, kept = _replay(room_log[0], "lookup_latest.py", [contract.TF, contract.MARKER_POSES])
    _expect(report, [])
    broadcasts = [
        tf
        for _, m, _ in kept
        if isinstance(m, msgs.TFMessage)
        for tf in m.transforms
        if tf.child_frame_id == contract.MARKER_FRAME
    ]
    # every one was stamped with the loop's time (a tick with a camera frame: the timer's
    # 10 Hz is the camera's), each a copy of an earlier frame's detection
    assert broadcasts and all(tf.header.stamp.ns % 100_000_000 == 0 for tf in broadcasts)
    measured = report.check("marker_frame.only_on_detection").measured
    assert f"{len(broadcasts)} broadcasts (marker_frame), 0 without a detection" in measured
    stored = [m for _, m, _ in kept if isinstance(m, msgs.FiducialTransformArray)]
    assert [m.header.frame_id for m in stored if m.transforms][-1:] == [contract.MAP]


def test_the_spin_and_the_navigator_both_command_the_explorer(
    room_log: tuple[Path, RecordResult],
) -> None:
    """The bug is in the outputs: ticks where /explorer/cmd_vel gets two different commands."""
    _, _, kept = _replay(room_log[0], "cmd_vel_conflict.py", [contract.cmd_vel("explorer")])
    by_tick: dict[int, list[msgs.Message | None]] = {}
    for _, m, t in kept:
        by_tick.setdefault(t, []).append(m)
    conflicts = [t for t, ms in by_tick.items() if len(ms) > 1 and len(set(map(repr, ms))) > 1]
    assert conflicts  # near target_1, until the navigator's goal ends
    # the mission's spin or stop against the navigator's command: closed loop, the later one in
    # the tick silently wins (the navigator's)


def test_the_rubric_catches_two_cmd_vel_publishers(room_log: tuple[Path, RecordResult]) -> None:
    _, report, _ = _replay(room_log[0], "cmd_vel_conflict.py")
    _expect(report, ["explorer.cmd_vel_one_publisher"])


# --- broadcasts as a TA sees them in RViz (rubric version 2, issue #32) -------------------------

LATE_BROADCASTER = """
    def on_markers(self, msg: FiducialTransformArray) -> None:
        # the frame is broadcast by the 20 Hz loop, a tick after its image, stamped "now"
        # (okritvik's callback; the assignment's sample code stamps with ros::Time::now())
        if not msg.transforms:
            if JUNK and not self.junked and self.empty is not None:
                # once: a frame on an image with no detection, after one without either
                self.junked = True
                self.send(Header(stamp=msg.header.stamp, frame_id=msg.header.frame_id),
                          Transform(translation=Vector3(z=1.0)))
            self.empty = msg.header.stamp
            return
        self.empty = None
        for f in msg.transforms:
            t = f.transform.translation
            if self.spinning and f.fiducial_id not in self.found and math.hypot(t.x, t.z) < 2.5:
                self.pending = (f.fiducial_id, msg.header, f.transform)

    def send(self, header: Header, transform: Transform) -> None:
        t = transform.translation
        moved = Transform(translation=Vector3(x=t.x + OFFSET_X, y=t.y, z=t.z),
                          rotation=transform.rotation)
        child = TransformStamped(header=header, child_frame_id=FRAME, transform=moved)
        self.tf.sendTransform(child)

    def on_tick(self) -> None:
        now = self.get_clock().now().to_msg()
        if self.pending is None or self.pending[1].stamp == now:
            return
        marker_id, header, transform = self.pending
        self.pending = None
        self.send(Header(stamp=now, frame_id=header.frame_id), transform)
        self.seen = (marker_id, now)

"""


def _late_broadcaster(
    tmp_path: Path, frame: str, *, offset_m: float = 0.0, junk: bool = False
) -> str:
    """examples/minimal_mission.py with its broadcaster as real packages write it: the frame
    named ``frame``, broadcast a tick (50 ms) after its image stamped with the loop's "now",
    ``offset_m`` off along the camera's x; ``junk``: also once on an image with no detection."""
    text = (EXAMPLES / "minimal_mission.py").read_text()
    start = text.index(
        "    def on_markers(self, msg: FiducialTransformArray) -> None:\n        for f"
    )
    end = text.index("    def on_timer(self)")
    text = text[:start] + LATE_BROADCASTER.lstrip("\n") + text[end:]
    timer = "        self.create_timer(0.1, self.on_timer)\n"
    assert timer in text and '"map", "marker_frame"' in text
    text = text.replace(
        timer,
        timer + "        self.create_timer(0.05, self.on_tick)\n"
        "        self.pending, self.empty, self.junked = None, None, False\n",
    )
    text = text.replace('"map", "marker_frame"', f'"map", {frame!r}')
    names = "TransformBroadcaster, TransformException"
    text = text.replace(names, "Transform, " + names)
    header = f"FRAME, OFFSET_X, JUNK = {frame!r}, {offset_m!r}, {junk!r}\n"
    mission = tmp_path / f"late_{frame}.py"
    mission.write_text(text.replace("\n\n\ndef goal(", "\n" + header + "\n\ndef goal(", 1))
    return str(mission)


def test_my_frame_stamped_a_tick_late_passes_the_broadcast_lines(
    room_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    """okritvik's shape (issue #32): ``my_frame``, stamped with the loop's "now" a tick after
    its image. Every line passes; the evidence names the frame and both stamps."""
    mission = _late_broadcaster(tmp_path, "my_frame")
    _, report, kept = _replay(room_log[0], mission, [contract.TF])
    _expect(report, [])
    line = report.check("marker_0.broadcast")
    assert line.measured.startswith("my_frame: ") and "cm from the marker" in line.measured
    stamps = [
        tf.header.stamp.ns
        for _, m, _ in kept
        if isinstance(m, msgs.TFMessage)
        for tf in m.transforms
        if tf.child_frame_id == "my_frame"
    ]
    assert stamps and all(s % 100_000_000 == 50_000_000 for s in stamps)  # between two images
    assert line.evidence.startswith(f"first broadcast: my_frame stamped {stamps[0] / 1e9:.3f} s")
    assert f"image {(stamps[0] - 50_000_000) / 1e9:.3f} s" in line.evidence


def test_a_broadcast_0_4_m_off_still_fails_the_broadcast_line(
    room_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    mission = _late_broadcaster(tmp_path, "my_frame", offset_m=0.4)
    _, report, _ = _replay(room_log[0], mission)
    _expect(report, ["marker_0.broadcast"])
    assert report.check("marker_0.broadcast").value == pytest.approx(0.4, abs=0.05)


def test_a_broadcast_with_no_detection_in_its_window_fails_only_on_detection(
    room_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    """Once, a frame on an image with no detection, the image before it had none either."""
    mission = _late_broadcaster(tmp_path, "target_0", junk=True)
    _, report, _ = _replay(room_log[0], mission)
    _expect(report, ["marker_frame.only_on_detection"])
    line = report.check("marker_frame.only_on_detection")
    assert ", 1 without a detection within 2 s, 0 with another parent" in line.measured
    assert line.evidence.startswith("first bad broadcast: target_0 stamped ")


# --- tf2's errors reach the user's code: uncaught, they crash the mission -----------------------


def test_listening_before_anything_was_broadcast_crashes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    world = tmp_path / "room.toml"
    save(one_room(), world)
    out = tmp_path / "run.mcap"
    mission = FAULTY / "listen_before_broadcast.py"
    code = main(
        [
            "record",
            "--scenario",
            str(world),
            "--mission",
            str(mission),
            "--out",
            str(out),
            "--quiet",
        ]
    )
    assert code == 4
    run = open_run(out)
    assert run.outcome == "crashed" and run.file_state == "complete"
    reason = run.outcome_reason
    assert f'File "{mission}"' in reason and "in on_timer" in reason
    assert reason.rstrip().splitlines()[-1].startswith("usar_replay.core.tf_tree.LookupException")
    assert '"marker_frame" passed to lookupTransform argument source_frame does not exist' in reason
    assert "The mission crashed:" in capsys.readouterr().out
    report = grade_file(out)
    # it crashed in the first loop, 0.1 s in: only the first frame's detection was published;
    # nothing was broadcast, so only_on_detection fails too (no credit without a broadcast)
    _expect_only_the_cmd_vel_lines_pass(report)  # marker_0.detected: as the detector saw


def test_looking_up_at_a_stamp_the_buffer_cannot_reach_crashes(tmp_path: Path) -> None:
    """tf2's own words (team 003): "Lookup would require extrapolation at time ..., but only
    time ... is in the buffer". What happened before the crash still counts."""
    out = tmp_path / "run.mcap"
    mission = FAULTY / "lookup_extrapolation.py"
    result = record(quick_room(), out, RunSettings(), mission=str(mission))
    assert result.outcome == "crashed"
    assert f'File "{mission}"' in result.outcome_reason
    assert "would require extrapolation" in result.outcome_reason
    assert "ExtrapolationException" in result.outcome_reason
    _expect(
        grade_file(out),
        [
            "explorer.home_before_follower",
            "follower.marker_0",
            "follower.home",
            "time_limit",
        ],
    )


# --- driving bugs: recorded closed loop -------------------------------------------------------


def test_the_follower_sent_into_the_wall(tmp_path: Path) -> None:
    out = tmp_path / "run.mcap"
    result = record(quick_room(), out, RunSettings(), mission=str(FAULTY / "follower_into_wall.py"))
    assert result.mission_done
    _expect(grade_file(out), ["follower.marker_0", "follower.home", "time_limit"])
    lines = [m.msg.msg for m in open_run(out).messages([contract.ROSOUT])]
    assert any("follower: goal goal_1 failed" in s for s in lines), lines


@pytest.mark.slow  # the two-marker corridor: ~100 s of sim time, ~2 min of wall time
def test_the_far_marker_is_stored_instead_of_the_near_one(tmp_path: Path) -> None:
    out = tmp_path / "run.mcap"
    result = record(corridor(), out, CORRIDOR_SETTINGS, mission=str(FAULTY / "far_marker.py"))
    assert result.mission_done
    assert set(result.markers_found) == {0}  # marker 0, in view 2.9 m away from target_1
    _expect(grade_file(out), ["marker_1.broadcast", "follower.marker_1"])


@pytest.mark.slow  # the two-marker corridor: ~100 s of sim time, ~2 min of wall time
def test_markers_visited_in_the_order_found(tmp_path: Path) -> None:
    out = tmp_path / "run.mcap"
    result = record(corridor(), out, CORRIDOR_SETTINGS, mission=str(FAULTY / "found_order.py"))
    assert result.mission_done and set(result.markers_found) == {0, 1}
    _expect(grade_file(out), ["follower.marker_1"])


# --- determinism: `usar replay` names the first divergence ------------------------------------

NOISY = """
import random
import time

from usar_replay.api import Node, String


def main():
    node = Node("noisy")
    pub = node.create_publisher(String, "/noisy")
    node.create_timer(0.2, lambda: pub.publish(String(data=repr({source}))))
"""


@pytest.mark.parametrize("source", ["time.time()", "random.random()"])
def test_a_mission_reading_the_clock_or_random_is_not_deterministic(
    source: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    mission = tmp_path / "noisy.py"
    mission.write_text(textwrap.dedent(NOISY.format(source=source)))
    out = tmp_path / "run.mcap"
    settings = RunSettings(record=RecordSettings(max_sim_time_s=1.0))
    assert record(one_room(), out, settings, mission=str(mission)).outcome == "max_sim_time"
    capsys.readouterr()
    assert main(["replay", str(out)]) == 1
    shown = capsys.readouterr().out
    assert "Replay does NOT reproduce the recording." in shown
    assert "not deterministic" in shown
    assert "First divergence: /noisy message #0 at sim time 1.200 s" in shown
    assert "data: recorded" in shown
