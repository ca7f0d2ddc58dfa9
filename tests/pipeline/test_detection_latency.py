"""``record.detection_latency_ticks``: the course's detections of a frame come with the next
tick, as a real ``aruco_detect`` answers a frame a little after Gazebo sent it.

With 1 (a ROS 1 package's default) the recorder detects while the mission takes in the frame;
the log keeps each detection's frame stamp, one tick before the tick it came in, stores the
value that ran, and replays bit for bit.
"""

from __future__ import annotations

from pathlib import Path

from example_worlds import quick_room

from usar_replay.core import contract, msgs
from usar_replay.core.settings import RecordSettings, RunSettings
from usar_replay.log.run import open_run
from usar_replay.pipeline.record import record, with_latency
from usar_replay.pipeline.replay import replay


def test_the_defaults_follow_the_engine() -> None:
    unset = RunSettings()
    assert unset.record.detection_latency_ticks is None
    assert with_latency(unset, 1).record.detection_latency_ticks == 1  # a ROS 1 package
    assert with_latency(unset, 0).record.detection_latency_ticks == 0  # a Python mission
    both = with_latency(RunSettings(record=RecordSettings(detection_latency_ticks=0)), 1)
    assert (both.record.actuation_latency_ticks, both.record.detection_latency_ticks) == (1, 0)


def test_the_built_in_mission_with_latent_detections_replays_bit_for_bit(tmp_path: Path) -> None:
    log = tmp_path / "latent.mcap"
    settings = RunSettings(
        record=RecordSettings(actuation_latency_ticks=1, detection_latency_ticks=1)
    )
    result = record(quick_room(), log, settings)
    assert result.outcome == "done" and len(result.found) == 1
    run = open_run(log)
    assert run.settings.record.detection_latency_ticks == 1
    tick_ns = 10**9 // run.settings.record.control_hz
    frames = {m.log_time_ns for m in run.messages([contract.IMAGE])}
    found = 0
    for m in run.messages([contract.FIDUCIALS]):
        assert isinstance(m.msg, msgs.FiducialTransformArray)
        stamp = m.msg.header.stamp.ns
        # a frame's answer, in the tick after it (never with the frame itself)
        assert stamp in frames and m.log_time_ns == stamp + tick_ns
        found += bool(m.msg.transforms)
    assert found > 0
    report = replay(log)
    assert report.identical, report.divergence
    assert report.topics[contract.FIDUCIALS].identical > 0
