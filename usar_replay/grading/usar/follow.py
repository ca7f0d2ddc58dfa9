"""Whether a broadcast frame follows the detections it is sent on (issue 50).

Why: a frame sent within a detection's window is not therefore the detection's. A package
that puts ``marker_frame`` 0.5 m ahead of its camera on every detection (the detected pose never
used) sent each broadcast "on a detection", and where the explorer faces the marker that place
is in front of it, like the follower's stand-off goal. A TA would not call that a broadcast of
the marker. So each broadcast judged as a detection's keeps its origin in the camera frame
(``b``), the detection's (``d``) and their offset, and the frame as a whole is:

* ``follows``: at least :data:`~.rules.STEADY` of its broadcasts are the detection (a copy), on
  the line from the camera to the detected marker (a stand-off along the ray), or at the same
  small offset from the detected pose (in the detection's axes or in ``map``'s; a goal in front
  of the marker's face), where that offset held while the frame moved (a frame that never moved
  shows nothing it follows);
* ``empty``: it is the camera itself, the empty transform of a ``broadcast()`` with nothing
  filled in (team 001's bug): the detection callback's broadcast, wrong in what it says, judged
  by where it shows (at the camera: off the marker);
* ``ignores``: the detections it was sent on moved, and it did not move with them: the part
  of its place a linear fit on the detection explains moves less than the match (a fixed
  offset ahead of the camera), or less than what is left unexplained (a fixed place with
  noise added);
* ``moves``: it moves with the detections, not in one of those shapes (wrong maths on the
  detection: a package that read its detections, its frame judged by where it shows);
* ``unknown``: the detections did not move (one view: a frame fixed ahead of the camera and a
  fixed offset from the marker are the same broadcasts).

The thresholds and their sources are :mod:`.rules`' (:data:`~.rules.FOLLOW_MATCH_M`,
:data:`~.rules.ONE_PLACE`).
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from usar_replay.core import msgs
from usar_replay.grading.usar.rules import BROADCAST_MATCH_M, FOLLOW_MATCH_M, ONE_PLACE, STEADY

__all__ = ["MAX_FOLLOW_SAMPLES", "FrameFollow", "Sample", "rotate", "sample"]

Vec = tuple[float, float, float]
MAX_FOLLOW_SAMPLES = 1024
"""Samples kept per frame name (the latest; a ring, so memory stays flat)."""


def rotate(q: msgs.Quaternion, v: Vec, *, inverse: bool = False) -> Vec:
    """``v`` rotated by the unit quaternion ``q`` (by its inverse when ``inverse``)."""
    ux, uy, uz = (-q.x, -q.y, -q.z) if inverse else (q.x, q.y, q.z)
    # v' = v + 2w (u x v) + 2 u x (u x v)
    tx = 2 * (uy * v[2] - uz * v[1])
    ty = 2 * (uz * v[0] - ux * v[2])
    tz = 2 * (ux * v[1] - uy * v[0])
    return (
        v[0] + q.w * tx + (uy * tz - uz * ty),
        v[1] + q.w * ty + (uz * tx - ux * tz),
        v[2] + q.w * tz + (ux * ty - uy * tx),
    )


@dataclass(frozen=True, slots=True)
class Sample:
    """One broadcast judged as a detection's, in the camera frame at its stamp."""

    b: Vec
    """The frame's origin."""
    d: Vec
    """The detected marker's origin."""
    in_marker: Vec
    """``b - d`` in the detection's axes (a goal 0.4 m out along the marker's normal)."""
    in_map: Vec
    """``b - d`` in ``map``'s axes (a goal at the marker minus (0.4, 0.4))."""
    exact: bool
    """A copy of the detection, or on the line from the camera to it, within the stand-off."""


def _sub(a: Vec, b: Vec) -> Vec:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _on_ray(b: Vec, d: Vec, small_m: float) -> bool:
    """``b`` on the segment from the camera to ``d``, short of it by at most ``small_m``."""
    dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
    if dd <= 0.0:
        return False
    s = (b[0] * d[0] + b[1] * d[1] + b[2] * d[2]) / dd
    off = math.dist(b, (s * d[0], s * d[1], s * d[2]))
    return 0.0 < s <= 1.0 and off <= FOLLOW_MATCH_M and math.dist(b, d) <= small_m


def sample(
    b: Vec, detection: msgs.Transform, camera_in_map: msgs.Quaternion, small_m: float
) -> Sample:
    """The sample of a broadcast at ``b`` (camera frame) sent on ``detection``; the camera's
    rotation in ``map`` at the broadcast's stamp; ``small_m``: the farthest a stand-off may be
    from the marker (the follower's stand-off plus the broadcast threshold)."""
    t = detection.translation
    d = (t.x, t.y, t.z)
    off = _sub(b, d)
    exact = math.dist(b, d) <= BROADCAST_MATCH_M or _on_ray(b, d, small_m)
    return Sample(
        b, d, rotate(detection.rotation, off, inverse=True), rotate(camera_in_map, off), exact
    )


def _median(points: Sequence[Vec]) -> Vec:
    return (
        statistics.median(p[0] for p in points),
        statistics.median(p[1] for p in points),
        statistics.median(p[2] for p in points),
    )


def _one_place(points: Sequence[Vec]) -> bool:
    """Do at least :data:`ONE_PLACE` of ``points`` lie within the match of their median?"""
    if not points:
        return True
    m = _median(points)
    return sum(math.dist(p, m) <= FOLLOW_MATCH_M for p in points) >= ONE_PLACE * len(points)


@dataclass(slots=True)
class FrameFollow:
    """One frame name's samples (the latest :data:`MAX_FOLLOW_SAMPLES`)."""

    samples: list[Sample] = field(default_factory=list)
    count: int = 0

    def keep(self, s: Sample) -> None:
        if len(self.samples) < MAX_FOLLOW_SAMPLES:
            self.samples.append(s)
        else:
            self.samples[self.count % MAX_FOLLOW_SAMPLES] = s
        self.count += 1

    def _steady_offset(self, small_m: float) -> set[int]:
        """The samples at the frame's usual offset from the detection (in either axes), where
        that offset is small and the frame moved while keeping it."""
        out: set[int] = set()
        for axes in ("in_marker", "in_map"):
            offsets = [getattr(s, axes) for s in self.samples]
            m = _median(offsets)
            if math.hypot(*m) > small_m:
                continue
            near = [i for i, o in enumerate(offsets) if math.dist(o, m) <= FOLLOW_MATCH_M]
            if not _one_place([self.samples[i].b for i in near]):
                out.update(near)
        return out

    def verdict(self, small_m: float) -> str:
        """``follows``, ``empty``, ``ignores``, ``moves`` or ``unknown`` (the module doc)."""
        n = len(self.samples)
        if not n:
            return "unknown"
        steady = self._steady_offset(small_m)
        follows = sum(s.exact or i in steady for i, s in enumerate(self.samples))
        if follows >= STEADY * n:
            return "follows"
        at_camera = sum(math.hypot(*s.b) <= FOLLOW_MATCH_M for s in self.samples)
        if at_camera >= ONE_PLACE * n:
            return "empty"
        if _one_place([s.d for s in self.samples]):
            return "unknown"
        return "moves" if self._moves_with() else "ignores"

    def _moves_with(self) -> bool:
        """Does the frame's place depend on the detection? A least-squares fit ``b = A d + c``
        over the samples: the part it explains must move more than the match, and more than
        twice what it leaves unexplained (a place with noise added is no function of the
        detection)."""
        b = np.array([s.b for s in self.samples], dtype=float)
        d = np.array([s.d for s in self.samples], dtype=float)
        x = np.hstack([d, np.ones((len(d), 1))])
        coef, *_ = np.linalg.lstsq(x, b, rcond=None)
        fitted = x @ coef
        explained = float(np.sqrt(np.mean(np.sum((fitted - fitted.mean(0)) ** 2, axis=1))))
        left = float(np.sqrt(np.mean(np.sum((b - fitted) ** 2, axis=1))))
        return explained > FOLLOW_MATCH_M and left <= max(FOLLOW_MATCH_M, explained / 2)
