"""`usar record` at the course camera's resolution (issue 43): the recorder renders and logs
the course camera's region where a marker can be in view, detects on it, and replay re-detects
from the log alone."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest
from conftest import one_room

from usar_replay.core import cdr, contract, msgs
from usar_replay.core.settings import RecordSettings, RunSettings
from usar_replay.log.run import open_run
from usar_replay.pipeline.record import RecordResult, record
from usar_replay.pipeline.replay import replay
from usar_replay.world.scenario import Scenario


def _course_room() -> Scenario:
    """The one-room world with the course world's camera: pixel fields 1920 px wide."""
    scn = one_room()
    return dataclasses.replace(scn, camera=dataclasses.replace(scn.camera, pixel_fields_width=1920))


@pytest.fixture(scope="module")
def course_log(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, RecordResult]:
    path = tmp_path_factory.mktemp("course-camera") / "room.mcap"
    return path, record(_course_room(), path, RunSettings())


def _stream(path: Path) -> list[tuple[str, str, int, bytes]]:
    return [
        (m.topic, m.publisher, m.log_time_ns, bytes(m.data))
        for m in open_run(path).messages(decode=False)
    ]


def test_detections_come_from_the_logged_regions(course_log: tuple[Path, RecordResult]) -> None:
    path, result = course_log
    assert result.mission_done and set(result.markers_found) == {0}
    assert open_run(path).settings.record.course_detection is True  # the value that ran
    stream = _stream(path)
    frames = {t for topic, _, t, _ in stream if topic == contract.IMAGE}
    regions: dict[int, msgs.CameraInfo] = {}
    for topic, who, t, data in stream:
        if topic == contract.COURSE_VIEW_INFO:
            assert who == "recorder"
            info = cdr.decode(data, msgs.CameraInfo.__msgtype__)
            assert isinstance(info, msgs.CameraInfo)
            regions[t] = info
    assert regions and set(regions) <= frames  # a region only with a frame
    assert len(regions) < len(frames)  # ... and only where a marker can be in view
    for info in regions.values():
        assert (info.width, info.height) == (1920, 1080)
        assert 0 < info.roi.width * info.roi.height < 1920 * 1080
    images = {t for topic, who, t, _ in stream if topic == contract.COURSE_VIEW_IMAGE}
    assert images == set(regions)
    seen = 0
    fx = regions[min(regions)].k[0]  # the course camera's focal length, 1207 px
    for topic, _, _, data in stream:
        if topic != contract.FIDUCIALS:
            continue
        found = cdr.decode(data, msgs.FiducialTransformArray.__msgtype__)
        assert isinstance(found, msgs.FiducialTransformArray)
        if found.transforms:
            seen += 1
            assert found.header.stamp.ns in regions  # detected in that frame's region
            # in the course camera's pixels (3 times the 640 px wide camera's focal length)
            f = found.transforms[0]
            side = fx * 0.15 / f.transform.translation.z
            assert 0.5 * side**2 < f.fiducial_area < 1.1 * side**2
    assert seen > 0 and fx > 1200
    # the mission is never sent the regions: its camera is the 320x240 one
    infos = [d for topic, who, _, d in stream if topic == contract.CAMERA_INFO]
    first = cdr.decode(infos[0], msgs.CameraInfo.__msgtype__)
    assert isinstance(first, msgs.CameraInfo) and (first.width, first.height) == (320, 240)


def test_replay_re_detects_from_the_log_alone(course_log: tuple[Path, RecordResult]) -> None:
    report = replay(course_log[0])
    assert report.identical and report.divergence is None
    t = report.topics[contract.FIDUCIALS]
    assert t.recorded == t.replayed == t.identical > 0


def test_the_same_run_gives_the_same_log_and_off_gives_no_region(
    course_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    again = tmp_path / "again.mcap"
    record(_course_room(), again, RunSettings())
    assert _stream(again) == _stream(course_log[0])
    off = tmp_path / "off.mcap"
    settings = RunSettings(record=RecordSettings(course_detection=False))
    result = record(_course_room(), off, settings)
    assert result.mission_done
    topics = {topic for topic, *_ in _stream(off)}
    assert contract.FIDUCIALS in topics and not topics & set(contract.COURSE_VIEW_TOPICS)
