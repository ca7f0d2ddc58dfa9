"""Whether a frame follows the detections it is sent on: a copy, a stand-off on the camera's
line, a fixed offset from the detected pose (in its axes or in map's) follow; a place fixed in
the camera frame while the detections move ignores them (the camera itself is the empty
transform's bug); one view tells nothing."""

from __future__ import annotations

import math

import pytest

from usar_replay.core import msgs
from usar_replay.grading.usar.follow import MAX_FOLLOW_SAMPLES, FrameFollow, rotate, sample

SMALL = 0.4 * math.sqrt(2) + 0.1
IDENTITY = msgs.Quaternion(w=1.0)
YAW_90 = msgs.Quaternion(z=math.sin(math.pi / 4), w=math.cos(math.pi / 4))
DETECTIONS = [(0.1 * k - 0.2, 0.05 * k, 0.7 + 0.1 * k) for k in range(5)]
"""Where the marker was seen, in the camera frame, over five images (it moved in view)."""


def _det(d: tuple[float, float, float], q: msgs.Quaternion = IDENTITY) -> msgs.Transform:
    return msgs.Transform(translation=msgs.Vector3(x=d[0], y=d[1], z=d[2]), rotation=q)


def _verdict(frame_of: object, camera: msgs.Quaternion = IDENTITY) -> str:
    f = FrameFollow()
    for d in DETECTIONS:
        b = frame_of(d)  # type: ignore[operator]
        f.keep(sample(b, _det(d), camera, SMALL))
    return f.verdict(SMALL)


def test_rotate_turns_a_vector_and_back() -> None:
    v = rotate(YAW_90, (1.0, 0.0, 0.0))
    assert v == pytest.approx((0.0, 1.0, 0.0))
    assert rotate(YAW_90, v, inverse=True) == pytest.approx((1.0, 0.0, 0.0))


def test_the_honest_shapes_follow() -> None:
    assert _verdict(lambda d: d) == "follows"
    half = _verdict(lambda d: (d[0] / 2, d[1] / 2, d[2] / 2))  # midway on the camera's line
    assert half == "follows"
    assert _verdict(lambda d: (d[0], d[1], d[2] - 0.4)) == "follows"  # a fixed offset
    # the same offset in map's axes with the camera turned: fixed in map, not in the camera
    v = rotate(YAW_90, (0.3, -0.2, 0.0), inverse=True)
    got = _verdict(lambda d: (d[0] + v[0], d[1] + v[1], d[2] + v[2]), YAW_90)
    assert got == "follows"


def test_a_place_fixed_ahead_of_the_camera_ignores_the_detections() -> None:
    assert _verdict(lambda d: (0.0, 0.0, 0.5)) == "ignores"
    assert _verdict(lambda d: (0.0, 0.0, 0.0)) == "empty"  # the camera itself: a bug
    # wrong maths on the detection (axes swapped): it moves with them, in no honest shape
    assert _verdict(lambda d: (d[2], d[0], d[1])) == "moves"
    # a big offset is no stand-off
    assert _verdict(lambda d: (d[0] + 3.0, d[1], d[2])) == "moves"


def test_one_view_tells_nothing_and_memory_stays_flat() -> None:
    """The camera and the marker both still: a fixed place ahead and a fixed offset from the
    marker are the same broadcasts; neither shows it follows (unless on the line)."""
    f = FrameFollow()
    assert f.verdict(SMALL) == "unknown"
    d = DETECTIONS[0]
    for _ in range(MAX_FOLLOW_SAMPLES + 10):
        f.keep(sample((0.0, 0.0, 0.5), _det(d), IDENTITY, SMALL))
    assert f.verdict(SMALL) == "unknown"
    assert len(f.samples) == MAX_FOLLOW_SAMPLES and f.count == MAX_FOLLOW_SAMPLES + 10
    ray = FrameFollow()
    ray.keep(sample((d[0] / 2, d[1] / 2, d[2] / 2), _det(d), IDENTITY, SMALL))
    assert ray.verdict(SMALL) == "follows"


def test_a_fixed_place_with_noise_added_still_ignores_the_detections() -> None:
    """0.5 m ahead of the camera plus a few centimetres of noise (or decimetres) per broadcast:
    no function of the detection; a frame at 1.5 times the detection (wrong maths) is one."""
    for noise in (0.03, 0.3):
        f = FrameFollow()
        for k in range(40):
            d = DETECTIONS[k % 5]
            jitter = noise * math.sin(7.3 * k), noise * math.cos(3.1 * k), noise * math.sin(k)
            f.keep(sample((jitter[0], jitter[1], 0.5 + jitter[2]), _det(d), IDENTITY, SMALL))
        assert f.verdict(SMALL) == "ignores", noise
    assert _verdict(lambda d: (1.5 * d[0], 1.5 * d[1], 1.5 * d[2])) == "moves"
