"""tf_tree against tf2's own published test cases, plus properties and an independent check."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from usar_replay.core import msgs
from usar_replay.core.tf_tree import (
    BufferCore,
    BufferFeeder,
    ConnectivityException,
    ExtrapolationException,
    InvalidArgumentException,
    LookupException,
    StaticTfMessageBuilder,
    TfMessageBuilder,
)

S = 1_000_000_000


def ts(
    parent: str,
    child: str,
    t: tuple[float, float, float] = (0, 0, 0),
    q: tuple[float, float, float, float] = (0, 0, 0, 1),
    stamp: int = 0,
) -> msgs.TransformStamped:
    return msgs.TransformStamped(
        header=msgs.Header(stamp=msgs.Time.from_ns(stamp), frame_id=parent),
        child_frame_id=child,
        transform=msgs.Transform(
            translation=msgs.Vector3(x=t[0], y=t[1], z=t[2]),
            rotation=msgs.Quaternion(x=q[0], y=q[1], z=q[2], w=q[3]),
        ),
    )


def xyz(t: msgs.TransformStamped) -> tuple[float, float, float]:
    v = t.transform.translation
    return (v.x, v.y, v.z)


def quat(t: msgs.TransformStamped) -> np.ndarray:
    r = t.transform.rotation
    q = np.array([r.x, r.y, r.z, r.w])
    return q if q[3] >= 0 else -q


def test_chain() -> None:
    b = BufferCore()
    b.set_transform(ts("a", "b", (1, 0, 0), stamp=S))
    b.set_transform(ts("b", "c", (1, 0, 0), stamp=S))
    assert xyz(b.lookup_transform("a", "c", 0)) == pytest.approx((2, 0, 0))
    assert xyz(b.lookup_transform("c", "a", 0)) == pytest.approx((-2, 0, 0))


def test_v_tree() -> None:
    b = BufferCore()
    for parent, child, t in [
        ("a", "b", (1, 0, 0)),
        ("b", "c", (1, 0, 0)),
        ("a", "f", (0, 1, 0)),
        ("f", "g", (0, 1, 0)),
    ]:
        assert b.set_transform(ts(parent, child, t, stamp=S))
    assert xyz(b.lookup_transform("c", "g", 0)) == pytest.approx((-2, 2, 0))
    assert xyz(b.lookup_transform("b", "f", 0)) == pytest.approx((-1, 1, 0))
    assert xyz(b.lookup_transform("f", "c", 0)) == pytest.approx((2, -1, 0))


def test_ring_45() -> None:
    b = BufferCore()
    names = "abcdefghi"
    for p, c in itertools.pairwise(names):
        b.set_transform(ts(p, c, (-0.292893, 0.707107, 0), (0, 0, 0.382683, 0.923880), S))
    ac = b.lookup_transform("a", "c", 0)
    assert xyz(ac) == pytest.approx((-1, 1, 0), abs=1e-5)
    assert quat(ac) == pytest.approx([0, 0, 0.707107, 0.707107], abs=1e-5)
    ae = b.lookup_transform("a", "e", 0)
    assert xyz(ae) == pytest.approx((-2, 0, 0), abs=1e-5)
    assert quat(ae) == pytest.approx([0, 0, 1, 0], abs=1e-5)
    ai = b.lookup_transform("a", "i", 0)
    assert xyz(ai) == pytest.approx((0, 0, 0), abs=1e-5)
    assert abs(quat(ai)[3]) == pytest.approx(1.0, abs=1e-5)


def test_interpolation() -> None:
    b = BufferCore()
    b.set_transform(ts("a", "b", (-9.4, -8.8, -8.2), stamp=200))
    b.set_transform(ts("a", "b", (-7.6, -7.0, -6.4), stamp=300))
    out = b.lookup_transform("a", "b", 250)
    assert xyz(out) == pytest.approx((-8.5, -7.9, -7.3))
    assert out.header.stamp.ns == 250


def test_static_with_dynamic_leaf() -> None:
    b = BufferCore()
    b.set_transform_static(ts("a", "b", (1, 0, 0)))
    b.set_transform_static(ts("b", "c", (1, 0, 0)))
    b.set_transform(ts("c", "d", (1, 0, 0), stamp=10 * S))
    assert b.can_transform("a", "d", 0)
    assert b.can_transform("a", "d", 10 * S)
    assert not b.can_transform("a", "d", 1 * S)
    assert not b.can_transform("a", "d", 100 * S)
    assert b.lookup_transform("a", "d", 0).header.stamp.ns == 10 * S


def test_errors_have_tf2_texts() -> None:
    b = BufferCore()
    b.set_transform(ts("a", "b", (1, 0, 0), stamp=S))
    b.set_transform(ts("x", "y", (1, 0, 0), stamp=S))
    with pytest.raises(ConnectivityException, match="not part of the same tree"):
        b.lookup_transform("a", "y", 0)
    with pytest.raises(LookupException) as err:
        b.lookup_transform("a", "marker_frame", 0)
    assert (
        str(err.value)
        == '"marker_frame" passed to lookupTransform argument source_frame does not exist. '
    )
    with pytest.raises(InvalidArgumentException, match="cannot start with a '/'"):
        b.lookup_transform("/a", "b", 0)
    with pytest.raises(ExtrapolationException, match=r"but only time 1\.000000 is in the buffer"):
        b.lookup_transform("a", "b", 2 * S)
    b.set_transform(ts("a", "b", (2, 0, 0), stamp=2 * S))
    with pytest.raises(
        ExtrapolationException, match=r"into the future\.  Requested time 3\.000000"
    ):
        b.lookup_transform("a", "b", 3 * S)
    with pytest.raises(
        ExtrapolationException, match=r"into the past.*from frame \[b\] to frame \[a\]"
    ):
        b.lookup_transform("a", "b", S // 2)


def test_refused_inserts() -> None:
    b = BufferCore()
    assert not b.set_transform(ts("a", "a"))
    assert not b.set_transform(ts("", "a"))
    assert not b.set_transform(ts("a", ""))
    assert not b.set_transform(ts("a", "b", (math.nan, 0, 0)))
    assert not b.set_transform(ts("a", "b", q=(0, 0, 0, 1.02)))
    # tf2 checks |q|^2 - 1 against 10e-3: 1.004^2 = 1.008 passes, 1.005^2 = 1.010025 does not
    assert b.set_transform(ts("a", "b", q=(0, 0, 0, 1.004)))
    assert not b.set_transform(ts("a", "b", q=(0, 0, 0, 1.005), stamp=1))
    assert b.set_transform(ts("/map", "/c", stamp=5))
    assert "c" in b.frames() and b.frames()["c"] == "map"


@pytest.mark.parametrize(
    ("msg", "errors"),
    [
        (ts("a", "a"), ["TF_SELF_TRANSFORM"]),
        (ts("/a", "a"), ["TF_SELF_TRANSFORM"]),
        (ts("", "a"), ["TF_NO_FRAME_ID"]),
        (ts("a", ""), ["TF_NO_CHILD_FRAME_ID"]),
        (ts("", ""), ["TF_SELF_TRANSFORM", "TF_NO_CHILD_FRAME_ID", "TF_NO_FRAME_ID"]),
        (ts("a", "b", (0, math.nan, 0)), ["TF_NAN_INPUT"]),
        (ts("a", "b", q=(0, 0, math.nan, 1)), ["TF_NAN_INPUT", "TF_DENORMALIZED_QUATERNION"]),
        (ts("a", "a", q=(0, 0, 0, 2)), ["TF_SELF_TRANSFORM", "TF_DENORMALIZED_QUATERNION"]),
        (ts("a", "b", q=(0, 0, 0, 0)), ["TF_DENORMALIZED_QUATERNION"]),
    ],
)
def test_a_refusal_logs_every_failing_check_in_tf2_order(
    msg: msgs.TransformStamped, errors: list[str], caplog: pytest.LogCaptureFixture
) -> None:
    """The insert checks are one condition on the fast path; a refused transform still logs
    each of tf2's errors that applies, in tf2's order, and leaves no trace in the buffer."""
    b = BufferCore()
    with caplog.at_level("ERROR", logger="usar_replay.core.tf_tree"):
        assert not b.set_transform(msg)
    assert [r.getMessage().split(":")[0] for r in caplog.records] == errors
    assert b.frames() == {}


def test_cache_time_prunes_and_refuses_old_data() -> None:
    b = BufferCore(cache_time=10.0)
    b.set_transform(ts("a", "b", stamp=1 * S))
    b.set_transform(ts("a", "b", stamp=20 * S))
    # tf2 prunes by the newest stamp *before* an insert: 1 s survives until the next insert
    assert b.can_transform("a", "b", 1 * S)
    assert not b.set_transform(ts("a", "b", stamp=5 * S))  # older than newest - cache_time
    assert not b.can_transform("a", "b", 1 * S)  # pruned by that (refused) insert
    assert b.set_transform(ts("a", "b", stamp=15 * S))


def test_no_interpolation_across_a_parent_change() -> None:
    b = BufferCore()
    b.set_transform(ts("p1", "c", (0, 0, 0), stamp=0 + S))
    b.set_transform(ts("p2", "c", (10, 0, 0), stamp=2 * S))
    b.set_transform_static(ts("root", "p1"))
    b.set_transform_static(ts("root", "p2"))
    assert xyz(b.lookup_transform("root", "c", int(1.5 * S))) == pytest.approx((0, 0, 0))


def test_same_frame_is_identity() -> None:
    b = BufferCore()
    b.set_transform(ts("a", "b", (1, 2, 3), stamp=S))
    out = b.lookup_transform("b", "b", 7)
    assert xyz(out) == (0, 0, 0) and out.header.stamp.ns == 7


def test_broadcaster_and_listener() -> None:
    b = BufferCore()
    listener = BufferFeeder(b)
    listener.on_tf_static(StaticTfMessageBuilder().send_transform(ts("map", "odom", (1, 0, 0))))
    msg = TfMessageBuilder().send_transform([ts("odom", "base", (0, 1, 0), stamp=S)])
    assert isinstance(msg, msgs.TFMessage) and len(msg.transforms) == 1
    listener.on_tf(msg)
    assert xyz(b.lookup_transform("map", "base", S)) == pytest.approx((1, 1, 0))
    assert b.frames() == {"base": "odom", "odom": "map"}
    assert "parent: 'map'" in b.all_frames_as_yaml()


def test_lookup_full_time_travel() -> None:
    b = BufferCore()
    b.set_transform(ts("map", "robot", (0, 0, 0), stamp=S))
    b.set_transform(ts("map", "robot", (1, 0, 0), stamp=2 * S))
    # where the robot was at 1 s, seen from the robot at 2 s: 1 m behind it
    out = b.lookup_transform_full("robot", 2 * S, "robot", S, "map")
    assert xyz(out) == pytest.approx((-1, 0, 0))


unit = st.floats(-1, 1, allow_nan=False)
coord = st.floats(-10, 10, allow_nan=False)


def _quat(data: st.DataObject) -> tuple[float, float, float, float]:
    q = np.array([data.draw(unit) for _ in range(4)])
    if np.linalg.norm(q) < 0.1:
        q = np.array([0, 0, 0, 1.0])
    q = q / np.linalg.norm(q)
    return tuple(float(v) for v in q)


@settings(max_examples=60, deadline=None)
@given(st.data())
def test_random_chain_matches_scipy(data: st.DataObject) -> None:
    """A chain equals the product of its links (composed independently with scipy)."""
    n = data.draw(st.integers(1, 6))
    b = BufferCore()
    rot = Rotation.identity()
    pos = np.zeros(3)
    frames = [f"f{i}" for i in range(n + 1)]
    for p, c in itertools.pairwise(frames):
        t = tuple(data.draw(coord) for _ in range(3))
        q = _quat(data)
        b.set_transform(ts(p, c, t, q, S))
        pos = pos + rot.apply(t)
        rot = rot * Rotation.from_quat(q)
    out = b.lookup_transform(frames[0], frames[-1], S)
    assert xyz(out) == pytest.approx(tuple(pos), abs=1e-9)
    got = Rotation.from_quat(quat(out))
    assert (got.inv() * rot).magnitude() < 1e-7
    back = b.lookup_transform(frames[-1], frames[0], S)
    inv_rot = Rotation.from_quat(quat(back))
    # lookup(a,b) composed with lookup(b,a) is the identity
    assert (inv_rot * got).magnitude() < 1e-7
    assert np.allclose(inv_rot.apply(xyz(out)) + np.array(xyz(back)), 0, atol=1e-9)


def test_a_flood_of_frame_names_is_bounded_and_counted() -> None:
    """A /tf flood of new names (issue 44): the buffer keeps at most max_frames names, counts
    what it dropped, and the frames it knew before still answer."""
    buf = BufferCore(max_frames=50)
    assert buf.set_transform(ts("map", "odom", (1, 0, 0)))
    for k in range(2000):
        buf.set_transform(ts("map", f"flood_{k}", stamp=k))
    assert len(buf._ids) <= 50 and len(buf._frames) <= 50
    assert buf.dropped == 2000 - 48
    assert buf.set_transform(ts("map", "odom", (2, 0, 0), stamp=S))  # a known name: kept
    assert xyz(buf.lookup_transform("map", "odom", msgs.Time.from_ns(S))) == (2.0, 0.0, 0.0)
    assert not buf.set_transform(ts("map", "one_more"))
