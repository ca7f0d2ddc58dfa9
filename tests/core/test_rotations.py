"""rotations: round trips, the wrap at +-pi, and agreement with scipy's Rotation."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from usar_replay.core import msgs
from usar_replay.core.rotations import (
    quat_from_yaw,
    wrap_angle,
    xyzw_from_yaw,
    yaw_from_quat,
    yaw_from_xyzw,
)

angle = st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False)
heading = st.floats(-math.pi + 1e-9, math.pi - 1e-9)


def same_angle(a: float, b: float, tol: float = 1e-9) -> bool:
    return abs(math.remainder(a - b, 2.0 * math.pi)) <= tol


@given(heading)
def test_yaw_round_trips(yaw: float) -> None:
    assert yaw_from_xyzw(*xyzw_from_yaw(yaw)) == pytest.approx(yaw, abs=1e-12)
    assert yaw_from_quat(quat_from_yaw(yaw)) == pytest.approx(yaw, abs=1e-12)
    q = quat_from_yaw(yaw)
    assert (q.x, q.y, q.z, q.w) == xyzw_from_yaw(yaw)


@given(angle)
def test_any_yaw_comes_back_wrapped(yaw: float) -> None:
    back = yaw_from_xyzw(*xyzw_from_yaw(yaw))
    assert -math.pi <= back <= math.pi
    assert same_angle(back, yaw, 1e-9 * max(1.0, abs(yaw)))


@given(angle)
def test_wrap_angle_range_and_value(a: float) -> None:
    w = wrap_angle(a)
    assert -math.pi <= w < math.pi
    assert same_angle(w, a, 1e-9 * max(1.0, abs(a)))


def test_wrap_angle_at_the_seam() -> None:
    """[-pi, pi): +pi and -pi both land on -pi; just inside either side stays put."""
    assert wrap_angle(math.pi) == pytest.approx(-math.pi)
    assert wrap_angle(-math.pi) == pytest.approx(-math.pi)
    assert wrap_angle(3 * math.pi) == pytest.approx(-math.pi)
    eps = 1e-9
    assert wrap_angle(math.pi - eps) == pytest.approx(math.pi - eps)
    assert wrap_angle(-math.pi + eps) == pytest.approx(-math.pi + eps)
    assert wrap_angle(math.pi + eps) == pytest.approx(-math.pi + eps)
    assert wrap_angle(0.0) == 0.0
    assert wrap_angle(2 * math.pi) == pytest.approx(0.0, abs=1e-15)
    assert wrap_angle(-0.5) == pytest.approx(-0.5)


@given(heading)
def test_xyzw_from_yaw_matches_scipy(yaw: float) -> None:
    ours = np.array(xyzw_from_yaw(yaw))
    ref = Rotation.from_euler("z", yaw).as_quat()  # scalar last: x, y, z, w
    assert np.allclose(ours, ref, atol=1e-12) or np.allclose(ours, -ref, atol=1e-12)


@given(
    st.floats(-math.pi, math.pi),
    st.floats(-1.4, 1.4),  # pitch away from gimbal lock, where yaw is not defined
    st.floats(-math.pi, math.pi),
)
def test_yaw_of_any_rotation_matches_scipy(yaw: float, pitch: float, roll: float) -> None:
    """The heading of a general rotation is scipy's intrinsic ZYX first angle."""
    r = Rotation.from_euler("ZYX", [yaw, pitch, roll])
    x, y, z, w = r.as_quat()
    assert same_angle(yaw_from_xyzw(x, y, z, w), r.as_euler("ZYX")[0], 1e-9)
    m = msgs.Quaternion(x=float(x), y=float(y), z=float(z), w=float(w))
    assert same_angle(yaw_from_quat(m), yaw, 1e-9)


@given(heading, heading)
def test_wrap_angle_is_the_short_way_between_headings(a: float, b: float) -> None:
    """wrap_angle(a - b) is the rotation scipy finds from heading b to heading a."""
    rel = Rotation.from_euler("z", a) * Rotation.from_euler("z", b).inv()
    d = wrap_angle(a - b)
    assert abs(d) == pytest.approx(rel.magnitude(), abs=1e-9)
    assert same_angle(d, rel.as_euler("ZYX")[0], 1e-9)
