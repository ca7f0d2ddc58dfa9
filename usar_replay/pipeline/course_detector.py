"""The course's aruco_detect, run by the recorder: detections the mission cannot forge.

Why here and not in the mission process: the rubric's "detected" lines must be computed only
from what the mission cannot forge. aruco_detect is part of the course's world (the students
launch it, they do not write it), so the recorder runs it, on the very bytes of each recorded
camera frame, with the run's ``[detector]`` settings, and hands its
``/fiducial_transforms`` to the mission as an input, written to the log as the ``sim``
publisher (the course's infrastructure). A mission that publishes ``/fiducial_transforms``
itself is refused (:class:`~usar_replay.node.executor.PublishPolicy`); one that brings its own
detector publishes on its own topic, compared by replay and never graded as a detection.

The detector keeps aruco_detect's ``enable_detections`` switch: a ``std_msgs/Bool`` the mission
publishes on :data:`~usar_replay.core.contract.ENABLE_DETECTIONS` turns it off and on from the
next camera frame (the built-in explorer enables it only while it searches at a target, so the
frames taken on the way are never decoded, as before). Everything is a pure function of the
recorded bytes and the mission's recorded outputs, so the detections replay exactly: they are
recorded inputs, which replay hands to the mission as they were logged.

Where the detections go: with ``record.detection_latency_ticks`` 0 (a Python mission's
default), in the frame's tick right after the camera frame, where the mission's own
``ArucoDetect`` used to deliver them (before odometry), so a mission sees the same messages in
the same order as when it ran the detector itself, and keeps its score. With 1 (a ROS 1
package's default), first in the next tick, stamped with their frame's time, as a real
``aruco_detect`` publishes its answer a little after Gazebo's frame: the recorder then detects
(:meth:`CourseDetector.after_send`) while the mission takes in the frame, not before it is
sent, and a frame tick no longer waits for the detector (some 2 ms a frame).

At the course camera's resolution (``record.course_detection``, the default): the course's
camera is 1920x1080, usar's frames 640x480. The recorder renders, with each frame, the course
camera's pixels around the markers that can be in view (:mod:`usar_replay.sim.course_view`)
and logs them as the ``recorder``'s :data:`~usar_replay.core.contract.COURSE_VIEW_TOPICS`
(never sent to the mission); the detector searches those instead of the 640x480 frame, so
poses, ``fiducial_area`` and ``image_error`` are the course camera's, and a frame with no
region (no marker can be in view) has no detection, without decoding anything. The regions
are rendered whatever the switch says, so a replay with other code or settings that switches
the detector otherwise still finds every region it needs in the log. The mission's
``CameraInfo`` stays the 640x480 images' own: it describes the images the mission receives.

The ROS 2 final project's world runs ros2_aruco's ``aruco_node`` the same way: the detections of
each frame with a marker in it, as ``ros2_aruco_interfaces/msg/ArucoMarkers`` on
``/aruco_markers`` (nothing for a frame without one, and no on/off switch: ros2_aruco has none).
A mission there that still publishes ``/aruco_markers`` itself (its own ``aruco_node``) is not
refused: the node API renames its messages to
:data:`~usar_replay.core.contract.MISSION_ARUCO_MARKERS` (recorded, compared by replay, never
graded), and its ``/aruco_markers`` subscribers receive the course's detections.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING

import cv2

from usar_replay.core import cdr, contract, msgs
from usar_replay.core.settings import DetectorParams
from usar_replay.sim.camera import encode_image
from usar_replay.sim.course_view import CourseCamera
from usar_replay.world.assignment import Assignment
from usar_replay.world.detect import aruco_markers, detect, in_camera_pixels

if TYPE_CHECKING:  # replay re-detects without a simulator: pybullet stays unloaded there
    from usar_replay.sim.simulator import Simulator

__all__ = ["CourseDetector", "course_view", "mission_inputs"]

Wire = tuple[str, str, bytes]
_FIDUCIALS_TYPE = msgs.FiducialTransformArray.__msgtype__
_ARUCO_TYPE = msgs.ArucoMarkers.__msgtype__


def mission_inputs(asg: Assignment, course_detections: bool) -> tuple[str, ...]:
    """The topics the world publishes to a mission: the simulator's, then (with the course's
    detector) ``/fiducial_transforms`` or ``/aruco_markers``."""
    extra = (asg.course_detections,) if course_detections and asg.course_detections else ()
    return (*asg.sim_topics, *extra)


def course_view(sim: Simulator, cam: CourseCamera, frame: msgs.CameraInfo) -> list[Wire]:
    """The recorder's messages for a camera frame (``frame``: its ``CameraInfo``) at the
    course camera's resolution: the region where a marker can be in view, as its
    ``CameraInfo`` (``roi`` set) and its grey levels (the detector looks at nothing else) as
    a PNG: lossless, as the course camera's raw images reach aruco_detect, and at a third of
    a colour PNG's encoding time; nothing when no marker can be in view."""
    where = sim.course_region(cam)
    if where is None:
        return []
    info = cam.info(frame.header, where)
    grey = cv2.cvtColor(sim.render_region(cam, where), cv2.COLOR_BGR2GRAY)
    data = encode_image(grey, "png")
    image = msgs.CompressedImage(header=frame.header, format="png", data=data)
    return [
        (contract.COURSE_VIEW_INFO, info.__msgtype__, cdr.encode(info)),
        (contract.COURSE_VIEW_IMAGE, image.__msgtype__, cdr.encode(image)),
    ]


class CourseDetector:
    """aruco_detect on the recorder's side: one instance per run, fed tick by tick."""

    def __init__(
        self,
        params: DetectorParams,
        asg: Assignment,
        pixel_scale: float = 1.0,
        latency_ticks: int = 0,
        course: bool = False,
    ) -> None:
        self.params = params
        self.course = course
        """Search the course camera's regions (:func:`course_view`) instead of the frame."""
        self.latency_ticks = latency_ticks
        """``record.detection_latency_ticks``: 1, a frame's detections come with the next
        tick (:meth:`deliver`, :meth:`after_send`)."""
        self._later: list[Wire] = []
        """The last frame's detections, for the next tick (latency 1)."""
        self.pixel_scale = pixel_scale
        """``fiducial_area`` and ``image_error`` in the pixels of a camera this many times the
        image's width (the world's ``camera.pixel_fields_width``: the course's 1920)."""
        self.topic = asg.course_detections
        self.image_topic = asg.image_topic
        self.info_topic = asg.camera_info_topic
        self.ros2_aruco = self.topic == contract.ARUCO_MARKERS
        """ros2_aruco's ``aruco_node`` (``ArucoMarkers`` for frames with a marker, no switch)
        rather than aruco_detect (a ``FiducialTransformArray`` per searched frame)."""
        self.enabled = True
        """aruco_detect starts enabled; the mission's ``Bool`` switches it."""
        self.seq = 0
        """Frames detected so far (aruco_detect's ``image_seq`` counts only those)."""
        self._info: tuple[bytes, msgs.CameraInfo] | None = None

    @classmethod
    def for_run(
        cls,
        params: DetectorParams,
        asg: Assignment,
        pixel_scale: float = 1.0,
        latency_ticks: int = 0,
        course: bool = False,
    ) -> CourseDetector | None:
        """The run's detector; None for an assignment whose world has none."""
        if not asg.course_detections:
            return None
        return cls(params, asg, pixel_scale, latency_ticks, course)

    def note_outputs(self, outputs: Iterable[tuple[str, msgs.Message]]) -> None:
        """The mission's outputs of a tick: an ``enable_detections`` switch acts from the next
        frame (the mission received this tick's frame before it could publish)."""
        if self.ros2_aruco:
            return
        for topic, value in outputs:
            if topic == contract.ENABLE_DETECTIONS and isinstance(value, msgs.Bool):
                self.enabled = value.data

    def deliver(self, wire: Sequence[Wire], view: Sequence[Wire] = ()) -> list[Wire]:
        """The tick's inputs as the mission is sent them: with latency 0
        (:meth:`add_detections`) with its frame's detections; with 1, with the last frame's
        detections first (:meth:`after_send` made them). ``view``: the tick's
        :func:`course_view` messages."""
        if not self.latency_ticks:
            return self.add_detections(wire, view)
        later, self._later = self._later, []
        return [*later, *wire]

    def after_send(self, wire: Sequence[Wire], view: Sequence[Wire] = ()) -> None:
        """With latency 1, detect the frame of a tick just sent (:meth:`deliver`'s result),
        for the next tick, with the switch as it is now, as :meth:`add_detections` would have
        before sending; with 0, nothing (the detections went with the frame)."""
        if self.latency_ticks:
            self._later = self._detections(wire, view)[1]

    def add_detections(self, wire: Sequence[Wire], view: Sequence[Wire] = ()) -> list[Wire]:
        """The tick's inputs with the detections of its camera frame right after the frame
        (unchanged when there is no frame, no ``CameraInfo`` yet, or detection is off; for
        ros2_aruco, also when the frame has no marker)."""
        out = list(wire)
        at, found = self._detections(wire, view)
        out[at:at] = found
        return out

    def _detections(self, wire: Sequence[Wire], view: Sequence[Wire]) -> tuple[int, list[Wire]]:
        """(where the frame's detections go: right after it, the message to publish, if any),
        the calibration noted on the way; (0, []) when the detector is off."""
        if not self.enabled:
            return 0, []
        for i, (topic, msgtype, data) in enumerate(wire):
            if topic == self.info_topic:
                self._note_info(data, msgtype)
            elif topic == self.image_topic and self._info is not None:
                image = cdr.decode(data, msgtype)
                assert isinstance(image, msgs.CompressedImage)
                found = self._search(image, view)
                self.seq += 1
                if not self.ros2_aruco:
                    return i + 1, [(self.topic, _FIDUCIALS_TYPE, cdr.encode(found))]
                if found.transforms:
                    return i + 1, [(self.topic, _ARUCO_TYPE, cdr.encode(aruco_markers(found)))]
                return i + 1, []
        return 0, []

    def _search(
        self, frame: msgs.CompressedImage, view: Sequence[Wire]
    ) -> msgs.FiducialTransformArray:
        """The frame's detections: in the course camera's region when :attr:`course` (none
        without a region), else in the frame itself, pixel fields scaled."""
        assert self._info is not None
        if not self.course:
            found = detect(frame, self._info[1], self.params, self.seq)
            return in_camera_pixels(found, self.pixel_scale)
        parts = {topic: (msgtype, data) for topic, msgtype, data in view}
        if contract.COURSE_VIEW_INFO not in parts or contract.COURSE_VIEW_IMAGE not in parts:
            return msgs.FiducialTransformArray(header=frame.header, image_seq=self.seq)
        info = cdr.decode(parts[contract.COURSE_VIEW_INFO][1], parts[contract.COURSE_VIEW_INFO][0])
        region = cdr.decode(
            parts[contract.COURSE_VIEW_IMAGE][1], parts[contract.COURSE_VIEW_IMAGE][0]
        )
        assert isinstance(info, msgs.CameraInfo) and isinstance(region, msgs.CompressedImage)
        found = detect(region, info, self.params, self.seq)
        return msgs.FiducialTransformArray(
            header=frame.header, image_seq=found.image_seq, transforms=found.transforms
        )

    def replay_tick(
        self,
        inputs: Sequence[Wire],
        recorded_outputs: Sequence[Wire],
        view: Sequence[Wire] = (),
    ) -> tuple[list[Wire], list[Wire], list[Wire]]:
        """Replay's re-run: (the tick's inputs with this detector's detections in place of the
        recorded ones, the recorded detections, the re-run's). The tick's *recorded*
        ``enable_detections`` switches then act from the next frame, as they did live (so the
        re-run needs no answer from the mission and replay keeps ticks in flight)."""
        recorded = [w for w in inputs if w[0] == self.topic]
        out = self.deliver([w for w in inputs if w[0] != self.topic], view)
        self.after_send(out, view)
        redone = [w for w in out if w[0] == self.topic]
        for topic, msgtype, data in recorded_outputs:
            if topic == contract.ENABLE_DETECTIONS and msgtype == msgs.Bool.__msgtype__:
                self.note_outputs([(topic, cdr.decode(data, msgtype))])
        return out, recorded, redone

    def _note_info(self, data: bytes, msgtype: str) -> None:
        if self._info is None or self._info[0] != data:
            info = cdr.decode(data, msgtype)
            assert isinstance(info, msgs.CameraInfo)
            self._info = (data, info)
