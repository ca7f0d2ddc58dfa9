"""`usar record` end to end on a one-room world: the log contract, determinism, Ctrl-C, the CLI."""

from __future__ import annotations

import io
import math
from pathlib import Path

import pytest
from clitools import start_usar
from conftest import one_room
from logtools import digest

from usar_replay.cli.main import main
from usar_replay.core import msgs
from usar_replay.grading.grade import grade_file
from usar_replay.log import bag
from usar_replay.log.run import open_run
from usar_replay.pipeline.record import RecordResult, print_summary, record
from usar_replay.world.scenario_toml import save

CONTRACT = {
    "/explorer/camera/rgb/image_raw/compressed": "sensor_msgs/msg/CompressedImage",
    "/explorer/camera/rgb/camera_info": "sensor_msgs/msg/CameraInfo",
    "/tf": "tf2_msgs/msg/TFMessage",
    "/tf_static": "tf2_msgs/msg/TFMessage",
    "/explorer/cmd_vel": "geometry_msgs/msg/Twist",
    "/follower/cmd_vel": "geometry_msgs/msg/Twist",
    "/explorer/odom": "nav_msgs/msg/Odometry",
    "/follower/odom": "nav_msgs/msg/Odometry",
    "/fiducial_transforms": "fiducial_msgs/msg/FiducialTransformArray",
    "/explorer/goal": "geometry_msgs/msg/PoseStamped",
    "/follower/goal": "geometry_msgs/msg/PoseStamped",
    "/explorer/goal_status": "diagnostic_msgs/msg/DiagnosticStatus",
    "/explorer/marker_poses": "fiducial_msgs/msg/FiducialTransformArray",
    "/rosout": "rcl_interfaces/msg/Log",
    "/ground_truth/explorer/pose": "geometry_msgs/msg/PoseStamped",
    "/ground_truth/follower/pose": "geometry_msgs/msg/PoseStamped",
    "/ground_truth/markers": "fiducial_msgs/msg/FiducialTransformArray",
    "/map": "nav_msgs/msg/OccupancyGrid",
}


def test_mission_completes_and_finds_the_marker(room_log: tuple[Path, RecordResult]) -> None:
    _path, result = room_log
    assert result.mission_done
    assert set(result.markers_found) == {0}
    assert result.marker_errors_m[0] < 0.05
    assert result.sim_duration_s < one_room().time_limit_s


def test_the_summary_counts_markers_as_the_rubric_does(
    room_log: tuple[Path, RecordResult],
) -> None:
    """The built-in mission's summary: found as `usar grade` counts them (marker_frame
    broadcasts looked up in map), and where the mission stored it."""
    path, result = room_log
    assert [f.marker_id for f in result.found] == [0] and result.markers_total == 1
    error = result.found[0].error_m
    assert error is not None and error < 0.10
    assert grade_file(path).check("marker_0.broadcast").measured == result.found[0].text
    text = io.StringIO()
    print_summary(result, text)
    lines = text.getvalue().splitlines()
    i = lines.index("Markers found: 1/1 (as `usar grade` counts them)")
    assert lines[i + 1] == f"  marker 0: {result.found[0].text}"
    assert lines[i + 2].startswith("    stored on /explorer/marker_poses at (")
    assert max(len(line) for line in lines) <= 100


def test_log_holds_the_whole_contract(room_log: tuple[Path, RecordResult]) -> None:
    path, result = room_log
    r = bag.BagReader(path)
    assert r.complete
    for topic, msgtype in CONTRACT.items():
        assert r.topics[topic].msgtype == msgtype, topic
    frames = r.topics["/explorer/camera/rgb/image_raw/compressed"].count
    assert frames == result.frames == r.topics["/explorer/camera/rgb/camera_info"].count
    # every frame at 10 Hz of sim time, none skipped
    assert frames == math.floor((r.end_ns - r.start_ns) / 1e8) + 1
    opened = open_run(path)
    assert opened.scenario == one_room()
    assert opened.settings_recorded and opened.settings.record.renderer == result.renderer
    assert opened.mission.target == "builtin" and len(opened.mission.sha256) == 64
    assert opened.outcome == "done" and opened.file_state == "complete"
    run = r.metadata[bag.RUN_METADATA]
    assert run["renderer"] == result.renderer and run["software"].startswith("usar-replay")
    # who published what: the simulator's and the mission's /tf are separate channels
    publishers = {(m.topic, m.publisher) for m in opened.messages(decode=False)}
    assert ("/tf", "sim") in publishers and ("/tf", "mission") in publishers
    assert {p for t, p in publishers if t.startswith("/ground_truth/")} == {"recorder"}
    assert {p for t, p in publishers if t == "/explorer/cmd_vel"} == {"mission"}


def test_marker_frame_only_with_detections(room_log: tuple[Path, RecordResult]) -> None:
    path, _ = room_log
    detected: set[int] = set()
    broadcast: list[msgs.TransformStamped] = []
    for m in bag.BagReader(path).messages(["/fiducial_transforms", "/tf"]):
        if isinstance(m.msg, msgs.FiducialTransformArray) and m.msg.transforms:
            detected.add(m.msg.header.stamp.ns)
        elif isinstance(m.msg, msgs.TFMessage):
            broadcast += [t for t in m.msg.transforms if t.child_frame_id == "marker_frame"]
    assert broadcast
    for t in broadcast:
        assert t.header.frame_id == "explorer_tf/camera_rgb_optical_frame"
        assert t.header.stamp.ns in detected


def test_same_scenario_gives_the_same_messages_via_the_cli(
    room_log: tuple[Path, RecordResult], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Record again through `usar record --scenario`: every message is identical."""
    scenario = tmp_path / "room.toml"
    save(one_room(), scenario)
    out = tmp_path / "again.mcap"
    code = main(["record", "--scenario", str(scenario), "--out", str(out), "--quiet"])
    assert code == 0
    text = capsys.readouterr().out
    assert "the mission said it was done" in text and "x real time" in text and "error" in text
    assert digest(out) == digest(room_log[0])


def test_ctrl_c_leaves_a_closed_interrupted_log(tmp_path: Path) -> None:
    out = tmp_path / "cut.mcap"
    ticks = 0

    def interrupt(p: object) -> None:
        nonlocal ticks
        ticks += 1
        if ticks == 60:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        record(one_room(), out, progress=interrupt)
    r = bag.BagReader(out)
    assert r.has_summary and r.status == "interrupted"
    assert r.topics["/explorer/odom"].count == 60
    assert not Path(str(out) + ".part").exists()


def test_invalid_scenario_is_one_line_exit_2(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text(
        'name = "x"\nwalls = []\nmarkers = []\n[aruco_lookup_locations]\ntarget_2 = [0, 0]\n'
    )
    import subprocess
    import sys

    out = subprocess.run(
        [sys.executable, "-m", "usar_replay.cli", "record", "--scenario", str(bad)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert out.returncode == 2
    assert out.stderr.strip().count("\n") == 0 and "missing target_1" in out.stderr


def test_an_existing_recording_is_never_overwritten_silently(
    room_log: tuple[Path, RecordResult], capsys: pytest.CaptureFixture[str]
) -> None:
    path, _ = room_log
    before = path.read_bytes()
    assert main(["record", "--out", str(path), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "exists" in err and "--overwrite" in err and err.count("\n") == 1
    assert path.read_bytes() == before


def test_ctrl_c_in_the_cli_exits_130_with_a_closed_log(tmp_path: Path) -> None:
    """A real SIGINT to `usar record`, sent once its first progress line shows it is running."""
    import signal

    scenario, out = tmp_path / "room.toml", tmp_path / "cut.mcap"
    save(one_room(), scenario)
    proc = start_usar("record", "--scenario", str(scenario), "--out", str(out))
    assert proc.stderr is not None
    assert proc.stderr.readline().startswith("sim ")  # the run is under way
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130
    assert "Traceback" not in err and "closed and readable, marked interrupted" in err
    r = bag.BagReader(out)
    assert r.has_summary and r.status == "interrupted" and r.message_count > 0
    assert not Path(str(out) + ".part").exists()


IDLE_MISSION = """from usar_replay.node.node import Node


def main():
    Node("idle")  # never says it is done
"""


@pytest.mark.slow
def test_a_mission_that_never_ends_stops_at_the_time_limit_and_its_grace(tmp_path: Path) -> None:
    """Issue 51: the TA's clock, not 1.5 x it; ``--max-sim-time`` still overrides."""
    from dataclasses import replace

    from usar_replay.core.settings import RecordSettings, RunSettings
    from usar_replay.pipeline.record import TIME_LIMIT_GRACE_S, hard_limit_s

    assert hard_limit_s(600.0) == 610.0 and TIME_LIMIT_GRACE_S == 10.0
    mission = tmp_path / "idle.py"
    mission.write_text(IDLE_MISSION, encoding="utf-8")
    world = replace(one_room(), time_limit_s=1.0)
    result = record(world, tmp_path / "idle.mcap", mission=str(mission))
    assert result.outcome == "time_limit"
    assert result.sim_duration_s == pytest.approx(11.0, abs=0.06)
    over = RunSettings(record=RecordSettings(max_sim_time_s=12.5))
    longer = record(world, tmp_path / "longer.mcap", over, mission=str(mission))
    assert longer.outcome == "max_sim_time"
    assert longer.sim_duration_s == pytest.approx(12.5, abs=0.06)
