"""sim/course_view: which part of the course's 1920x1080 camera can hold a detectable marker."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from usar_replay.sim.course_view import CourseCamera, Region, marker_corners, region
from usar_replay.sim.simulator import camera_intrinsics
from usar_replay.world.scenario import Marker, course_world

CAM = CourseCamera(1920, 1080, 1.3439)
MARKER = Marker(id=1, x=0.0, y=0.0, z=0.2, yaw=0.0)  # faces +x


def _pose(x: float, y: float, yaw: float) -> tuple[np.ndarray, np.ndarray]:
    """A camera at (x, y, 0.117) looking along ``yaw``: (eye, optical-frame rotation)."""
    c, s = math.cos(yaw), math.sin(yaw)
    fwd, left, up = np.array([c, s, 0.0]), np.array([-s, c, 0.0]), np.array([0.0, 0.0, 1.0])
    return np.array([x, y, 0.117]), np.column_stack([-left, -up, fwd])


def test_the_course_camera_is_the_worlds_pixel_fields_width_at_16_by_9() -> None:
    cam = CourseCamera.of(course_world().camera)
    assert cam == CourseCamera(1920, 1080, course_world().camera.hfov)
    assert CourseCamera.of(dataclasses.replace(course_world().camera, pixel_fields_width=0)) is None
    assert cam.intrinsics() == camera_intrinsics(1920, 1080, cam.hfov)


def test_a_marker_in_front_gets_a_region_around_its_corners() -> None:
    eye, rot = _pose(2.0, 0.1, math.pi)
    where = region(eye, rot, (MARKER,), CAM)
    assert where is not None
    fx, fy, cx, cy = CAM.intrinsics()
    pts = (marker_corners(MARKER) - eye) @ rot
    u, v = fx * pts[:, 0] / pts[:, 2] + cx, fy * pts[:, 1] / pts[:, 2] + cy
    assert where.x + 32 <= u.min() and u.max() <= where.x + where.width - 32
    assert where.y + 32 <= v.min() and v.max() <= where.y + where.height - 32
    assert where.width * where.height < 0.1 * 1920 * 1080  # a small part of the frame


def test_the_region_stays_inside_the_image() -> None:
    eye, rot = _pose(0.6, 0.0, math.pi - 0.5)  # the marker near the image's right edge
    where = region(eye, rot, (MARKER,), CAM)
    assert where is not None
    assert where.x >= 0 and where.y >= 0
    assert where.x + where.width <= 1920 and where.y + where.height <= 1080


@pytest.mark.parametrize(
    "why, pose",
    [
        ("looking away", (2.0, 0.0, 0.0)),
        ("behind the marker", (-2.0, 0.0, 0.0)),
        ("out of the frame's side", (2.0, 0.0, math.pi - 1.2)),
        ("too far to be detected", (40.0, 0.0, math.pi)),
    ],
)
def test_no_region_where_no_marker_can_be_detected(
    why: str, pose: tuple[float, float, float]
) -> None:
    assert region(*_pose(*pose), (MARKER,), CAM) is None, why


def test_two_markers_share_one_region_holding_both() -> None:
    other = dataclasses.replace(MARKER, id=2, y=0.6)
    eye, rot = _pose(3.0, 0.3, math.pi)
    one = region(eye, rot, (MARKER,), CAM)
    both = region(eye, rot, (MARKER, other), CAM)
    assert one is not None and both is not None
    assert both.width > one.width and both.x <= one.x
    assert both.roi().x_offset == both.x and both.roi().width == both.width


def test_a_region_is_a_ros_region_of_interest() -> None:
    roi = Region(10, 20, 300, 200).roi()
    assert (roi.x_offset, roi.y_offset, roi.width, roi.height) == (10, 20, 300, 200)
