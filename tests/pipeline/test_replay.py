"""`usar replay`: bit-for-bit reproduction of the real recorded log, divergences found exactly
where a log was altered, regression mode, streaming, and one-line errors for bad input."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from clitools import one_error_line, usar
from logtools import rewrite, truncate_at

from usar_replay.cli.main import main
from usar_replay.core import msgs
from usar_replay.core.contract import CAMERA_INFO, FIDUCIALS, IMAGE
from usar_replay.core.errors import UsageError
from usar_replay.core.settings import DetectorParams, RunSettings, apply_overrides, load
from usar_replay.log import bag
from usar_replay.log.run import open_run
from usar_replay.pipeline.record import RecordResult
from usar_replay.pipeline.replay import MISSION_TF_KEY, outputs_digest, replay
from usar_replay.sim.camera import encode_image as encode_png
from usar_replay.world.detect import decode_image, detect, detect_with_corners

CAMERA_INFO_TOPIC, IMAGE_TOPIC = CAMERA_INFO, IMAGE


def _changed(**overrides: str) -> RunSettings:
    return apply_overrides(RunSettings(), overrides, default_group="mission")


def test_replay_reproduces_the_recording(
    room_log: tuple[Path, RecordResult], capsys: pytest.CaptureFixture[str]
) -> None:
    path = room_log[0]
    assert main(["replay", str(path)]) == 0
    out = capsys.readouterr().out
    assert "Replay reproduces the recording bit for bit." in out
    digest = outputs_digest(path)
    assert f"Replayed outputs' sha256: {digest}" in out
    # every output topic of the log is compared, every message identical
    report = replay(path, window=1)  # and the same with one tick in flight
    assert report.identical and report.digest == digest and report.divergence is None
    publishers = {(m.topic, m.publisher) for m in open_run(path).messages(decode=False)}
    mission_topics = {topic for topic, who in publishers if who == "mission"}
    assert {"/explorer/cmd_vel", "/follower/cmd_vel", "/rosout"} <= mission_topics
    # the course's detector is the world's (trusted): an input, re-run and compared by replay
    assert ("/fiducial_transforms", "sim") in publishers and "/fiducial_transforms" not in (
        mission_topics
    )
    for topic in (mission_topics - {"/tf"}) | {"/fiducial_transforms"}:
        t = report.topics[topic]
        assert t.recorded == t.replayed == t.identical > 0, topic
    counts = bag.BagReader(path).topics
    # the explorer enables its detector only while it searches at a target
    assert 0 < report.topics["/fiducial_transforms"].identical < counts[IMAGE_TOPIC].count
    assert report.topics[MISSION_TF_KEY].identical >= 1
    assert not report.regression and report.mission == "builtin"


def _frame_with_one_pixel_changed(
    path: Path,
) -> tuple[int, bytes]:
    """The first frame the mission detected a marker in, and its PNG with one pixel changed so
    that the detection's bytes change (searched deterministically near the marker's corners).
    Only frames with a recorded detection qualify: the explorer's detector is off while it
    drives."""
    params = DetectorParams()
    info: msgs.CameraInfo | None = None
    detected = {
        m.msg.header.stamp.ns
        for m in bag.BagReader(path).messages([FIDUCIALS])
        if isinstance(m.msg, msgs.FiducialTransformArray) and m.msg.transforms
    }
    for m in bag.BagReader(path).messages([CAMERA_INFO_TOPIC, IMAGE_TOPIC]):
        if isinstance(m.msg, msgs.CameraInfo):
            info = m.msg
            continue
        assert isinstance(m.msg, msgs.CompressedImage) and info is not None
        if m.msg.header.stamp.ns not in detected:
            continue
        found, corners = detect_with_corners(m.msg, info, params)
        if not found.transforms:
            continue
        before = bag.encode(found)
        img = decode_image(m.msg.data)
        assert np.array_equal(decode_image(encode_png(img)), img)  # PNG is lossless
        for cu, cv in np.rint(corners[found.transforms[0].fiducial_id]).astype(int):
            for dv, du in [(0, 0), (0, 1), (1, 0), (0, -1), (-1, 0), (1, 1), (-1, -1)]:
                for delta in (80, -80, 160, -160):
                    u, v = int(cu + du), int(cv + dv)
                    changed = img.copy()
                    changed[v, u] = np.clip(changed[v, u].astype(int) + delta, 0, 255)
                    data = encode_png(changed)
                    after = detect(replace(m.msg, data=data), info, params)
                    if bag.encode(after) != before:
                        assert int(np.count_nonzero(np.any(changed != img, axis=2))) == 1
                        return m.log_time_ns, data
    raise AssertionError("no single pixel changes a detection")


def test_one_pixel_changed_diverges_at_exactly_that_frame(
    room_log: tuple[Path, RecordResult], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    t_frame, data = _frame_with_one_pixel_changed(room_log[0])
    path = tmp_path / "pixel.mcap"

    def edit(m: bag.BagMessage) -> msgs.Message | None:
        if m.topic == IMAGE_TOPIC and m.log_time_ns == t_frame:
            assert isinstance(m.msg, msgs.CompressedImage)
            return replace(m.msg, data=data)
        return None

    rewrite(room_log[0], path, edit)
    assert main(["replay", str(path)]) == 1
    out = capsys.readouterr().out
    assert "Replay does NOT reproduce the recording." in out
    report = replay(path)
    d = report.divergence
    assert d is not None
    assert d.topic == "/fiducial_transforms"
    assert d.recorded_ns == d.replayed_ns == t_frame
    assert d.field.startswith("transforms[0].") and d.recorded_value != d.replayed_value
    assert f"at sim time {t_frame / 1e9:.3f} s" in out and d.field in out


def test_an_altered_recorded_output_names_its_field(
    room_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    """The comparison is field by field: a recorded cmd_vel changed in one field is named."""
    path = tmp_path / "cmd.mcap"
    altered: list[int] = []

    def edit(m: bag.BagMessage) -> msgs.Message | None:
        msg = m.msg
        if not altered and isinstance(msg, msgs.Twist) and m.topic == "/follower/cmd_vel":
            altered.append(m.log_time_ns)
            return replace(msg, angular=replace(msg.angular, z=0.5))
        return None

    rewrite(room_log[0], path, edit)
    report = replay(path)
    d = report.divergence
    assert d is not None and d.topic == "/follower/cmd_vel" and d.recorded_ns == altered[0]
    assert d.field == "angular.z" and d.recorded_value == "0.5"
    cmd = report.topics["/follower/cmd_vel"]
    assert cmd.identical == cmd.recorded - 1 == cmd.replayed - 1
    assert report.digest == outputs_digest(room_log[0])  # the replay itself did not change


def test_regression_mode_reports_what_changed(room_log: tuple[Path, RecordResult]) -> None:
    """DICT_5X5_50 cannot see the 4x4 marker: detections lost, stored pose lost; and the
    comparison stays streaming although the replay publishes far fewer messages."""
    report = replay(room_log[0], _changed(**{"detector.dictionary": "DICT_5X5_50"}))
    assert not report.identical and report.regression and report.settings_changed
    lines = report.changes.lines()
    assert any(line.startswith("marker 0: detections lost:") for line in lines), lines
    assert "marker 0: stored pose lost" in lines
    assert report.changes.detections_replayed == {} and report.changes.markers_replayed == {}
    follower = report.topics["/follower/cmd_vel"]
    assert follower.recorded > 100 and follower.replayed <= 2


def test_regression_mode_reports_a_moved_marker(room_log: tuple[Path, RecordResult]) -> None:
    """Without corner refinement the marker is still seen on the same frames, but its stored
    map pose moves by a couple of centimetres."""
    report = replay(room_log[0], _changed(**{"detector.corner_refinement": "none"}))
    lines = report.changes.lines()
    assert not any("detections" in line for line in lines), lines
    moved = [line for line in lines if line.startswith("marker 0: stored map pose moved")]
    assert len(moved) == 1, lines
    cm = float(moved[0].split("moved ")[1].removesuffix(" cm"))
    assert 0.0 < cm < 10.0
    assert report.divergence is not None and report.divergence.topic == "/fiducial_transforms"


def test_regression_mode_via_the_command(
    room_log: tuple[Path, RecordResult],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    caplog: pytest.LogCaptureFixture,
) -> None:
    """Changed outputs exit 1 unless --expect-changes; with --grade the lost marker fails."""
    path = str(room_log[0])
    js = tmp_path / "r.json"
    dictionary = "detector.dictionary=DICT_5X5_50"
    assert main(["replay", "--set", dictionary, "--json", str(js), path]) == 1
    captured = capsys.readouterr()
    out = captured.out.splitlines()
    # the grader sees sim time in order after the replayed mission stops early (it used to get
    # in-flight ticks late: tf2's TF_OLD_DATA on stderr and /tf samples dropped)
    assert "TF_OLD_DATA" not in captured.err + caplog.text
    # the rubric delta is shown without --grade: the log holds ground truth
    delta = out[out.index("Rubric lines that change (recorded -> replayed):") :]
    assert delta[1].split()[:6] == ["marker_0.detected", "PASS", "12/12", "->", "FAIL", "0/12"]
    assert delta[1].endswith("-12 pts")
    assert out[-1] == "Replay does NOT reproduce the recording: see the changes above."
    import json

    doc = json.loads(js.read_text())["replay"]["rubric_delta"]
    ids = [row["id"] for row in doc["lines"]]
    assert ids[:2] == ["marker_0.detected", "marker_0.broadcast"]
    assert doc["total_before"] == 60.0 and doc["total_after"] <= 40.0
    lost = sum(row["points"] for row in doc["lines"])
    assert doc["total_after"] - doc["total_before"] == lost
    total = f"  total 60 -> {doc['total_after']:g} of 60 ({lost:+g} pts)"
    assert total in delta and all(f"  {i} " in "\n".join(delta) for i in ids)
    assert (
        main(["replay", "--expect-changes", "--set", "detector.dictionary=DICT_5X5_50", path]) == 0
    )
    out = capsys.readouterr().out
    assert "Changes with changed settings:" in out and "marker 0: stored pose lost" in out
    assert out.splitlines()[-1].endswith("(expected: see the changes).")
    toml = tmp_path / "settings.toml"
    toml.write_text('[detector]\ndictionary = "DICT_5X5_50"\n')
    junit = tmp_path / "g.xml"
    assert main(["replay", "--settings", str(toml), "--grade", "--junit", str(junit), path]) == 1
    out = capsys.readouterr().out
    assert "marker 0: stored pose lost" in out
    fail_lines = [ln for ln in out.splitlines() if ln.startswith("FAIL")]
    assert any("marker_0.detected" in ln for ln in fail_lines)
    assert not any("explorer.target_1" in ln for ln in fail_lines)  # ground truth is recorded
    assert "marker_0.detected" in junit.read_text()


def test_replay_grade_grades_the_replayed_outputs(
    room_log: tuple[Path, RecordResult], capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["replay", "--grade", str(room_log[0])]) == 0
    out = capsys.readouterr().out
    assert "bit for bit" in out and "(replayed)" in out and "Total: 60 / 60 points: PASS" in out


def test_a_truncated_log_replays_as_far_as_it_goes(
    room_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    path = tmp_path / "cut.mcap"
    last = truncate_at(room_log[0], path, bag.BagReader(room_log[0]).start_ns + 15_000_000_000)
    report = replay(path)
    assert report.log_problem and "truncated" in report.log_problem
    assert report.identical  # what is there reproduces
    assert report.topics["/fiducial_transforms"].identical > 0
    assert report.topics["/fiducial_transforms"].recorded < 616
    out = usar("replay", path.name, cwd=tmp_path)  # a short path: the note has room for the time
    assert out.returncode == 3 and "Traceback" not in out.stderr
    assert "bit for bit" in out.stdout
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and "incomplete" in lines[0] and f"{last / 1e9:.3f}" in lines[0]
    assert len(lines[0]) <= 100


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["--set", "detector.dictionary=DICT_9X9_1"], "is not one of"),
        (["--set", "detector.colour=red"], "unknown setting"),
        (["--set", "max_detection_range=far"], "expected a number"),
        (["--set", "settle_frames"], "expected NAME=VALUE"),
        (["--set", "detector=DICT_5X5_50"], "set one of its fields"),
        (["--set", "settle_frames=-3"], "out of range"),
        (["--set", "mission.follower_tolerance=0"], "out of range"),
        (["--tick-timeout", "0"], "--tick-timeout"),
    ],
)
def test_bad_settings_are_one_line_exit_2(
    room_log: tuple[Path, RecordResult], args: list[str], needle: str
) -> None:
    one_error_line(usar("replay", *args, str(room_log[0])), 2, needle)


def test_settings_toml_errors(tmp_path: Path) -> None:
    bad = tmp_path / "s.toml"
    bad.write_text("[detector\n")
    with pytest.raises(UsageError, match="invalid TOML"):
        load(RunSettings, bad)
    bad.write_text("[camera]\nwidth = 3\n")
    with pytest.raises(UsageError, match="unknown setting"):
        load(RunSettings, bad)
    bad.write_text("[detector]\nmarker_size = [1, 2]\n")
    with pytest.raises(UsageError, match="expected a number"):
        load(RunSettings, bad)
    good = tmp_path / "g.toml"
    good.write_text("[mission]\nspin_speed = 0.2\n[detector]\nmarker_size = 0.2\n")
    s = load(RunSettings, good)
    assert s.mission.spin_speed == 0.2 and s.detector.marker_size == 0.2


def test_replay_bad_inputs_are_one_line(
    room_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    one_error_line(usar("replay", str(tmp_path / "none.mcap")), 2, "no such file")
    text = tmp_path / "text.mcap"
    text.write_text("hello")
    one_error_line(usar("replay", str(text)), 3, "not an MCAP")
    no_scenario = tmp_path / "no_scenario.mcap"
    rewrite(room_log[0], no_scenario, keep_scenario=False)
    one_error_line(usar("replay", str(no_scenario)), 3, "scenario.toml")
    no_odom = tmp_path / "no_odom.mcap"
    rewrite(room_log[0], no_odom, lambda m: False if m.topic == "/explorer/odom" else None)
    one_error_line(usar("replay", str(no_odom)), 3, "/explorer/odom", "missing")
    no_truth = tmp_path / "no_truth.mcap"
    rewrite(room_log[0], no_truth, lambda m: False if m.topic.startswith("/ground_truth") else None)
    one_error_line(usar("replay", "--grade", str(no_truth)), 3, "/ground_truth/", "missing")
    bad_th = tmp_path / "t.toml"
    bad_th.write_text("[thresholds]\nhome_m = 0\n")
    one_error_line(usar("replay", "--grade", "--thresholds", str(bad_th), str(room_log[0])), 2)


def test_replay_writes_machine_reports_without_grading(
    room_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    """--json/--junit/--csv work without --grade: the comparison itself, versioned."""
    import json
    import xml.etree.ElementTree as ET

    js, xml, csv_ = tmp_path / "r.json", tmp_path / "r.xml", tmp_path / "r.csv"
    args = ["replay", "--json", str(js), "--junit", str(xml), "--csv", str(csv_), str(room_log[0])]
    assert main(args) == 0
    doc = json.loads(js.read_text())
    assert doc["schema_version"] == 1 and doc["recordings"] == []
    rep = doc["replay"]
    assert rep["identical"] and rep["first_divergence"] is None and rep["mission"] == "builtin"
    assert rep["digest_sha256"] == outputs_digest(room_log[0])
    assert {t["topic"] for t in rep["topics"]} >= {"/fiducial_transforms", "/follower/cmd_vel"}
    root = ET.parse(xml).getroot()
    assert root.get("failures") == "0" and int(root.get("tests", "0")) == len(rep["topics"]) + 1
    assert csv_.read_text().splitlines()[0].startswith("schema_version,source,topic")
    # an output over the input is refused before any work
    one_error_line(usar("replay", "--json", str(room_log[0]), str(room_log[0])), 2, "input")
