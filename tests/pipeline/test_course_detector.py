"""pipeline/course_detector: the course's detector on the recorder's side, fed real encoded
frames of an ArUco marker (drawn with OpenCV) tick by tick."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from usar_replay.core import cdr, contract, msgs
from usar_replay.core.settings import DetectorParams
from usar_replay.pipeline.course_detector import CourseDetector, course_view, mission_inputs
from usar_replay.sim.camera import encode_image
from usar_replay.sim.course_view import CourseCamera
from usar_replay.sim.simulator import Simulator
from usar_replay.world.assignment import ROS2_FINAL, USAR, Assignment
from usar_replay.world.scenario import course_world

INFO = msgs.CameraInfo(
    height=480,
    width=640,
    distortion_model="plumb_bob",
    d=(0.0,) * 5,
    k=(500.0, 0.0, 320.0, 0.0, 500.0, 240.0, 0.0, 0.0, 1.0),
    r=(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
    p=(500.0, 0.0, 320.0, 0.0, 0.0, 500.0, 240.0, 0.0, 0.0, 0.0, 1.0, 0.0),
)


def _frame(marker_id: int | None) -> bytes:
    canvas = np.full((480, 640, 3), 255, np.uint8)
    if marker_id is not None:
        dictionary = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_4X4_50)
        tile = cv2.aruco.generateImageMarker(dictionary, marker_id, 120)
        canvas[180:300, 260:380] = cv2.cvtColor(tile, cv2.COLOR_GRAY2BGR)
    return cdr.encode(msgs.CompressedImage(format="png", data=encode_image(canvas)))


def _tick(
    asg: Assignment, marker_id: int | None, *, info: bool = True
) -> list[tuple[str, str, bytes]]:
    image_topic, info_topic = asg.image_topic, asg.camera_info_topic
    odom = ("/x/odom", msgs.Odometry.__msgtype__, cdr.encode(msgs.Odometry()))
    items = [(image_topic, msgs.CompressedImage.__msgtype__, _frame(marker_id)), odom]
    if info:
        items.insert(0, (info_topic, msgs.CameraInfo.__msgtype__, cdr.encode(INFO)))
    return items


def test_the_inputs_a_mission_gets() -> None:
    assert mission_inputs(USAR, True)[-1] == contract.FIDUCIALS
    assert contract.FIDUCIALS not in mission_inputs(USAR, False)
    assert mission_inputs(ROS2_FINAL, True)[-1] == contract.ARUCO_MARKERS


def test_detections_come_right_after_the_frame() -> None:
    det = CourseDetector.for_run(DetectorParams(), USAR)
    assert det is not None
    assert det.add_detections(_tick(USAR, 7, info=False)) == _tick(USAR, 7, info=False)
    out = det.add_detections(_tick(USAR, 7))
    assert [w[0] for w in out] == [
        contract.CAMERA_INFO,
        contract.IMAGE,
        contract.FIDUCIALS,
        "/x/odom",
    ]
    found = cdr.decode(out[2][2], out[2][1])
    assert isinstance(found, msgs.FiducialTransformArray)
    assert [f.fiducial_id for f in found.transforms] == [7] and found.image_seq == 0
    empty = det.add_detections(_tick(USAR, None))  # aruco_detect: a message per searched frame
    assert cdr.decode(empty[2][2], empty[2][1]) == msgs.FiducialTransformArray(image_seq=1)


def test_pixel_fields_are_in_the_course_cameras_pixels() -> None:
    """With the world's ``pixel_scale`` (the course world: 1920 / 640 = 3) the published
    ``fiducial_area`` is 9 times and ``image_error`` 3 times the frame's own; the pose is the
    same."""

    def first(scale: float) -> msgs.FiducialTransform:
        det = CourseDetector.for_run(DetectorParams(), USAR, scale)
        assert det is not None
        out = det.add_detections(_tick(USAR, 7))
        found = cdr.decode(out[2][2], out[2][1])
        assert isinstance(found, msgs.FiducialTransformArray)
        return found.transforms[0]

    own, course = first(1.0), first(3.0)
    assert own.fiducial_area == pytest.approx(120.0**2, rel=0.05)
    assert course.fiducial_area == own.fiducial_area * 9
    assert course.image_error == own.image_error * 3
    assert (course.transform, course.object_error) == (own.transform, own.object_error)


def test_the_missions_switch_acts_from_the_next_frame() -> None:
    det = CourseDetector(DetectorParams(), USAR)
    det.note_outputs([(contract.ENABLE_DETECTIONS, msgs.Bool(data=False))])
    assert det.add_detections(_tick(USAR, 7)) == _tick(USAR, 7)
    det.note_outputs([(contract.ENABLE_DETECTIONS, msgs.Bool(data=True))])
    assert len(det.add_detections(_tick(USAR, 7))) == 4


def test_ros2_aruco_publishes_only_frames_with_a_marker_and_has_no_switch() -> None:
    det = CourseDetector(DetectorParams(), ROS2_FINAL)
    assert det.add_detections(_tick(ROS2_FINAL, None)) == _tick(ROS2_FINAL, None)
    det.note_outputs([(contract.ENABLE_DETECTIONS, msgs.Bool(data=False))])
    out = det.add_detections(_tick(ROS2_FINAL, 2))
    assert out[2][0] == contract.ARUCO_MARKERS
    markers = cdr.decode(out[2][2], out[2][1])
    assert isinstance(markers, msgs.ArucoMarkers) and markers.marker_ids == (2,)


def test_replay_puts_its_own_detections_in_place_of_the_recorded() -> None:
    det = CourseDetector(DetectorParams(), USAR)
    forged = (
        contract.FIDUCIALS,
        msgs.FiducialTransformArray.__msgtype__,
        cdr.encode(
            msgs.FiducialTransformArray(transforms=(msgs.FiducialTransform(fiducial_id=9),))
        ),
    )
    tick = _tick(USAR, 7)
    inputs = [*tick[:2], forged, tick[2]]
    switch_off = [(contract.ENABLE_DETECTIONS, msgs.Bool.__msgtype__, cdr.encode(msgs.Bool()))]
    out, recorded, redone = det.replay_tick(inputs, switch_off)
    assert recorded == [forged] and len(redone) == 1 and redone[0] != forged
    assert [w[0] for w in out] == [
        contract.CAMERA_INFO,
        contract.IMAGE,
        contract.FIDUCIALS,
        "/x/odom",
    ]
    assert not det.enabled  # the recorded switch, for the next frame


def test_with_a_latency_a_frames_detections_come_first_in_the_next_tick() -> None:
    """``record.detection_latency_ticks`` 1: the frame goes out alone, the recorder detects
    after sending it (with the switch as it was), and the next tick starts with the answer,
    as :meth:`add_detections` would have put it after the frame."""
    now = CourseDetector(DetectorParams(), USAR)
    later = CourseDetector(DetectorParams(), USAR, latency_ticks=1)
    framed, plain = _tick(USAR, 7), [w for w in _tick(USAR, None) if w[0] == "/x/odom"]
    expected = now.add_detections(framed)[2]
    sent = later.deliver(framed)
    assert sent == framed  # nothing detected yet
    later.after_send(sent)
    nxt = later.deliver(plain)
    assert nxt == [expected, *plain]
    assert later.deliver(plain) == plain  # delivered once
    # switched off before the frame was sent: no detections the tick after
    later.note_outputs([(contract.ENABLE_DETECTIONS, msgs.Bool(data=False))])
    later.after_send(later.deliver(framed))
    assert later.deliver(plain) == plain


def test_replay_delivers_a_latent_detection_where_it_was_recorded() -> None:
    """Replay re-runs a latency-1 detector as the recorder ran it: the recorded detections
    (first in the tick after the frame) compared with the re-run's of the tick before."""
    live = CourseDetector(DetectorParams(), USAR, latency_ticks=1)
    framed, plain = _tick(USAR, 7), [w for w in _tick(USAR, None) if w[0] == "/x/odom"]
    recorded_ticks = []
    for wire in (framed, plain, plain):
        sent = live.deliver(wire)
        live.after_send(sent)
        recorded_ticks.append(sent)
    again = CourseDetector(DetectorParams(), USAR, latency_ticks=1)
    results = [again.replay_tick(inputs, []) for inputs in recorded_ticks]
    assert [out for out, _, _ in results] == recorded_ticks
    assert [len(redone) for _, _, redone in results] == [0, 1, 0]
    assert [recorded == redone for _, recorded, redone in results] == [True, True, True]


def _course_tick() -> tuple[list[tuple[str, str, bytes]], list[tuple[str, str, bytes]]]:
    """A course-world frame facing marker 0 from its target: (the tick's inputs, the
    recorder's :func:`course_view` of it)."""
    scn = course_world()
    cam = CourseCamera.of(scn.camera)
    assert cam is not None
    with Simulator(scn, renderer="tiny") as sim:
        tx, ty = scn.targets[0]
        m = scn.marker_by_id(0)
        sim.teleport("explorer", tx, ty, math.atan2(m.y - ty, m.x - tx) + 0.2)
        info = sim.camera_info()
        frame = msgs.CompressedImage(
            header=info.header, format="png", data=encode_image(sim.render_camera())
        )
        view = course_view(sim, cam, info)
        again = course_view(sim, cam, info)
    assert view == again  # the same scene gives the same bytes
    wire = [
        (contract.CAMERA_INFO, info.__msgtype__, cdr.encode(info)),
        (contract.IMAGE, frame.__msgtype__, cdr.encode(frame)),
    ]
    return wire, view


def test_at_the_course_resolution_the_region_is_searched() -> None:
    wire, view = _course_tick()
    assert [w[0] for w in view] == list(contract.COURSE_VIEW_TOPICS)
    det = CourseDetector(DetectorParams(), USAR, pixel_scale=3.0, course=True)
    out = det.add_detections(wire, view)
    assert [w[0] for w in out] == [contract.CAMERA_INFO, contract.IMAGE, contract.FIDUCIALS]
    found = cdr.decode(out[-1][2], out[-1][1])
    assert isinstance(found, msgs.FiducialTransformArray)
    assert [f.fiducial_id for f in found.transforms] == [0]
    assert found.header == cdr.decode(wire[1][2], wire[1][1]).header  # the frame's stamp
    assert found.transforms[0].fiducial_area > 10000  # the course camera's pixels, unscaled
    # the same tick detected again gives the same bytes
    again = CourseDetector(DetectorParams(), USAR, pixel_scale=3.0, course=True)
    assert again.add_detections(wire, view) == out


def test_at_the_course_resolution_a_frame_without_a_region_is_never_decoded() -> None:
    """No marker can be in view (no region): an empty detection, without decoding the frame
    (these bytes are no image: decoding them would raise DetectError)."""
    info = (contract.CAMERA_INFO, msgs.CameraInfo.__msgtype__, cdr.encode(INFO))
    header = msgs.Header(stamp=msgs.Time.from_ns(5), frame_id="cam")
    junk = msgs.CompressedImage(header=header, format="png", data=b"not an image")
    wire = [info, (contract.IMAGE, junk.__msgtype__, cdr.encode(junk))]
    det = CourseDetector(DetectorParams(), USAR, course=True)
    out = det.add_detections(wire)
    found = cdr.decode(out[-1][2], out[-1][1])
    assert found == msgs.FiducialTransformArray(header=header, image_seq=0)
    assert det.seq == 1  # a searched frame all the same, as aruco_detect counts it


def test_replay_re_detects_from_the_logged_region() -> None:
    wire, view = _course_tick()
    live = CourseDetector(DetectorParams(), USAR, course=True)
    recorded = live.add_detections(wire, view)
    again = CourseDetector(DetectorParams(), USAR, course=True)
    _, was, redone = again.replay_tick(recorded, [], view)
    assert was == redone and redone[0][0] == contract.FIDUCIALS
