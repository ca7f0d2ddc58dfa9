"""Where in the course's 1920x1080 camera a marker can be: the region the recorder renders.

Why: the course's TurtleBot3 waffle camera is 1920x1080 (``COURSE_CAMERA``); usar records
640x480 frames, whose raw pose error at 4-6 m is several times the course camera's
(bench/bench_course_detect.py). Rendering the whole course frame costs some 6 times a 640x480
frame, yet the detector only needs the pixels around a marker. The recorder knows the world,
so it projects every marker's corners with the course camera's intrinsics and renders, at the
course camera's pixel density, only the rectangle that holds the candidates (plus a margin):
nothing at all when no marker can be in view.

A marker is a candidate when its printed face is toward the camera, its four corners are in
front of the camera, its projected quadrilateral overlaps the image, and its projected
perimeter is at least half the smallest one OpenCV's detector accepts in the full image
(``minMarkerPerimeterRate`` times the image's larger side): each test only drops a marker the
full-size detector could not find. The region is rendered with the
whole scene; the simulator's depth test (the frame's depth buffer) drops a marker wholly
behind a wall or the other robot, and any marker left behind one simply is not in the pixels.

The margin (:data:`MARGIN_PX`, and :data:`MARGIN_RATE` of the region's size) keeps the
detector's adaptive thresholding (windows up to 23 px) and corner refinement away from the
region's edges, so the region detects as the same pixels of a full render do.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from usar_replay.core import msgs
from usar_replay.world.scenario import COURSE_CAMERA, CameraSettings, Marker

__all__ = [
    "MARGIN_PX",
    "MARGIN_RATE",
    "MIN_PERIMETER_RATE",
    "CourseCamera",
    "Region",
    "marker_corners",
    "region",
]

MARGIN_PX = 32
"""Pixels around the candidates' bounding box (more than the 23 px threshold window)."""
MARGIN_RATE = 0.25
"""And this share of the box's larger side: a marker's white surroundings stay in the region."""
MIN_PERIMETER_RATE = 0.03
"""OpenCV's default ``minMarkerPerimeterRate``: a marker's perimeter must be this share of the
image's larger side to be detected."""
NEAR_PLANE = 0.02
"""m: corners nearer than this along the optical axis are not in view (the renderer's)."""


@dataclass(frozen=True, slots=True)
class Region:
    """A rectangle of the course camera's image, in pixels (x right, y down): as
    ``sensor_msgs/RegionOfInterest`` says it."""

    x: int
    y: int
    width: int
    height: int

    def roi(self) -> msgs.RegionOfInterest:
        """As the ``roi`` of the region's ``CameraInfo``."""
        return msgs.RegionOfInterest(
            x_offset=self.x, y_offset=self.y, height=self.height, width=self.width
        )


@dataclass(frozen=True, slots=True)
class CourseCamera:
    """The camera the detections are computed for: its size and horizontal field of view.

    The intrinsics follow the simulator's camera model (``camera_intrinsics``: square pixels,
    principal point at ``(W/2, H/2 - 1)``), so a region rendered from it lines up with a full
    render at this size pixel for pixel."""

    width: int
    height: int
    hfov: float

    @classmethod
    def of(cls, cam: CameraSettings) -> CourseCamera | None:
        """The course camera of a world whose detections are in another camera's pixels
        (``camera.pixel_fields_width``, the course's 1920): as wide, the course camera's
        16:9 shape, the world's field of view; None for a world detected at its own images."""
        if not cam.pixel_fields_width:
            return None
        width = cam.pixel_fields_width
        height = round(width * COURSE_CAMERA[1] / COURSE_CAMERA[0])
        return cls(width, height, cam.hfov)

    def intrinsics(self) -> tuple[float, float, float, float]:
        """(fx, fy, cx, cy) in OpenCV's pixel convention (the simulator's camera model)."""
        fov_v = 2.0 * math.atan(math.tan(self.hfov / 2.0) * self.height / self.width)
        f = (self.height / 2.0) / math.tan(fov_v / 2.0)
        return f, f, self.width / 2.0, self.height / 2.0 - 1.0

    def info(self, header: msgs.Header, where: Region | None = None) -> msgs.CameraInfo:
        """This camera's ``CameraInfo`` (plumb_bob, no distortion), with ``roi`` the rendered
        region (ROS's meaning: the image that comes with it is that part of this camera's)."""
        fx, fy, cx, cy = self.intrinsics()
        return msgs.CameraInfo(
            header=header,
            height=self.height,
            width=self.width,
            distortion_model="plumb_bob",
            d=(0.0, 0.0, 0.0, 0.0, 0.0),
            k=(fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0),
            r=(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
            p=(fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0),
            roi=where.roi() if where is not None else msgs.RegionOfInterest(),
        )


def marker_corners(m: Marker) -> np.ndarray:
    """The marker's four corners in ``map`` (rows), as the simulator builds its quad: in the
    marker's y-z plane, facing its +x."""
    c, s, h = math.cos(m.yaw), math.sin(m.yaw), m.size / 2.0
    local = [(-h, -h), (h, -h), (h, h), (-h, h)]  # (along the marker's y, along z)
    return np.array([(m.x - s * dy, m.y + c * dy, m.z + dz) for dy, dz in local])


def region(
    eye: np.ndarray,
    rot: np.ndarray,
    markers: tuple[Marker, ...],
    cam: CourseCamera,
    hidden: Callable[[np.ndarray], bool] | None = None,
) -> Region | None:
    """The rectangle of ``cam``'s image (optical centre ``eye`` and optical-frame rotation
    ``rot`` in map) that holds every marker it may detect, with the margin; None when none
    can be detected (the module's docstring says which tests). ``hidden``: given a marker's
    corners in the optical frame, True when it is wholly hidden behind something nearer (the
    simulator's depth test of the frame it goes with)."""
    fx, fy, cx, cy = cam.intrinsics()
    boxes: list[tuple[float, float, float, float]] = []
    for m in markers:
        normal = np.array([math.cos(m.yaw), math.sin(m.yaw), 0.0])
        if float(normal @ (eye - np.array([m.x, m.y, m.z]))) <= 0.0:
            continue  # its back is to the camera
        pts = (marker_corners(m) - eye) @ rot
        if bool(np.any(pts[:, 2] <= NEAR_PLANE)):
            continue
        u = fx * pts[:, 0] / pts[:, 2] + cx
        v = fy * pts[:, 1] / pts[:, 2] + cy
        if u.max() < 0 or v.max() < 0 or u.min() > cam.width or v.min() > cam.height:
            continue
        perimeter = float(np.sum(np.hypot(np.diff(u, append=u[0]), np.diff(v, append=v[0]))))
        if perimeter < 0.5 * MIN_PERIMETER_RATE * max(cam.width, cam.height):
            continue
        if hidden is not None and hidden(pts):
            continue
        boxes.append((float(u.min()), float(v.min()), float(u.max()), float(v.max())))
    if not boxes:
        return None
    u0, v0 = min(b[0] for b in boxes), min(b[1] for b in boxes)
    u1, v1 = max(b[2] for b in boxes), max(b[3] for b in boxes)
    pad = MARGIN_PX + MARGIN_RATE * max(u1 - u0, v1 - v0)
    x0 = max(0, math.floor(u0 - pad))
    y0 = max(0, math.floor(v0 - pad))
    x1 = min(cam.width, math.ceil(u1 + pad))
    y1 = min(cam.height, math.ceil(v1 + pad))
    return Region(x0, y0, x1 - x0, y1 - y0)
