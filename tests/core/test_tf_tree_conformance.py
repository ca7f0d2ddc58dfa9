"""tf_tree against tf2's early-return paths, case by case from tf2's own source and tests.

Every test names where its cases come from in ros2/geometry2 (the same on humble, jazzy and
rolling): ``tf2/src/buffer_core.cpp`` (``lookupTransformImpl``, ``canTransform``,
``validateFrameId``, ``setTransformImpl``), ``tf2/src/cache.cpp`` (``TimeCache``),
``tf2_py/src/tf2_py.cpp`` and the tests ``test_tf2/test/buffer_core_test.cpp``,
``tf2/test/simple_tf2_core.cpp``, ``tf2/test/cache_unittest.cpp`` and
``tf2_py/test/test_buffer_core.py``.
"""

from __future__ import annotations

import pytest

from usar_replay.core import msgs
from usar_replay.core.tf_tree import (
    BufferCore,
    ConnectivityException,
    ExtrapolationException,
    InvalidArgumentException,
    LookupException,
    TransformException,
)

S = 1_000_000_000


def ts(parent: str, child: str, x: float = 0.0, stamp: int = 0) -> msgs.TransformStamped:
    return msgs.TransformStamped(
        header=msgs.Header(stamp=msgs.Time.from_ns(stamp), frame_id=parent),
        child_frame_id=child,
        transform=msgs.Transform(
            translation=msgs.Vector3(x=x), rotation=msgs.Quaternion(x=0, y=0, z=0, w=1)
        ),
    )


def x_of(t: msgs.TransformStamped) -> float:
    return t.transform.translation.x


def is_identity(t: msgs.TransformStamped) -> bool:
    tr, r = t.transform.translation, t.transform.rotation
    return (tr.x, tr.y, tr.z, r.x, r.y, r.z, r.w) == (0, 0, 0, 0, 0, 0, 1)


ZERO, OLD, VALID, FUTURE = 0, 5 * S, 15 * S, 25 * S


def two_link_tree() -> BufferCore:
    """test_tf2 buffer_core_test.cpp, TEST(tf, canTransform) / TEST(tf, lookupTransform): a
    two-link tree between 10 s and 20 s."""
    b = BufferCore()
    for i in range(10, 20):
        assert b.set_transform(ts("parent", "child", 1.0, i * S))
        assert b.set_transform(ts("parent", "other_child", 2.0, i * S))
    return b


# --- a frame looked up in itself: tf2's short cut before validation ---------------------------


@pytest.mark.parametrize("frame", ["some_frame", "", "/child", "NO_SUCH"])
@pytest.mark.parametrize("time", [ZERO, OLD, VALID, FUTURE])
def test_self_lookup_of_an_unknown_frame_is_identity(frame: str, time: int) -> None:
    """buffer_core.cpp lookupTransformImpl: ``if (target_frame == source_frame)`` returns the
    identity before ``validateFrameId`` (even an empty or '/'-led id); the stamp is the asked
    time, or for time 0 the frame's newest stamp, and 0 when the frame has no cache.
    buffer_core_test.cpp TEST(tf, lookupTransform) "confirm zero length list disconnected
    will return true"."""
    b = two_link_tree()
    out = b.lookup_transform(frame, frame, time)
    assert is_identity(out)
    assert out.header.stamp.ns == time
    assert out.header.frame_id == frame and out.child_frame_id == frame
    assert b.can_transform(frame, frame, time)  # TEST(tf, canTransform), same frame
    assert b.can_transform(frame, frame, time, return_debug_tuple=True) == (True, "")


@pytest.mark.parametrize("time", [OLD, VALID, FUTURE])
def test_self_lookup_of_a_dynamic_frame_keeps_the_asked_time(time: int) -> None:
    """TEST(tf, lookupTransform) / TEST(tf, canTransform): "Same Frame should pass for all
    times" (old, valid and future: no extrapolation check at all)."""
    b = two_link_tree()
    out = b.lookup_transform("child", "child", time)
    assert is_identity(out) and out.header.stamp.ns == time
    assert b.can_transform("child", "child", time)


def test_self_lookup_at_time_zero_takes_the_frames_newest_stamp() -> None:
    """lookupTransformImpl: time 0 -> ``cache->getLatestTimestamp()``: the newest stamp of a
    dynamic frame, 0 for a static one (StaticCache::getLatestTimestamp), 0 for a frame that is
    only ever a parent (no cache), 0 for a cleared dynamic frame (empty TimeCache)."""
    b = two_link_tree()
    b.set_transform_static(ts("world", "parent", 3.0, 7 * S))
    assert b.lookup_transform("child", "child", 0).header.stamp.ns == 19 * S
    assert b.lookup_transform("parent", "parent", 0).header.stamp.ns == 0  # static
    assert b.lookup_transform("world", "world", 0).header.stamp.ns == 0  # parent only
    b.clear()
    assert b.lookup_transform("child", "child", 0).header.stamp.ns == 0
    assert b.lookup_transform("child", "child", msgs.Time(sec=3)).header.stamp.ns == 3 * S


def test_full_lookup_validates_every_frame_first() -> None:
    """buffer_core.cpp lookupTransformImpl (full): the three ``validateFrameId`` calls come
    before the two halves, so a frame in itself through an unknown fixed frame still fails."""
    b = two_link_tree()
    with pytest.raises(LookupException) as err:
        b.lookup_transform_full("child", VALID, "child", VALID, "nowhere")
    assert str(err.value) == (
        '"nowhere" passed to lookupTransform argument fixed_frame does not exist. '
    )
    with pytest.raises(LookupException):
        b.lookup_transform_full("x", VALID, "x", VALID, "child")
    assert not b.can_transform_full("x", VALID, "x", VALID, "child")
    ok, why = b.can_transform_full("x", VALID, "x", VALID, "child", return_debug_tuple=True)
    assert not ok
    assert why == (
        'Invalid frame ID "x" passed to canTransform argument target_frame - frame does not exist'
    )


def test_full_lookup_takes_the_stamp_of_its_target_half() -> None:
    """lookupTransformImpl (full) writes ``time_out`` twice; the second half
    (``fixed -> target`` at ``target_time``) is what the caller gets."""
    b = two_link_tree()
    out = b.lookup_transform_full("child", ZERO, "parent", VALID, "child")
    assert out.header.stamp.ns == 19 * S  # target half: child in child at 0 -> newest, 19 s
    out = b.lookup_transform_full("child", VALID, "parent", OLD, "parent")
    assert out.header.stamp.ns == VALID  # the source half (parent in parent) is at 5 s


# TEST(tf, canTransform), "Advanced API Tests": (target_time, source, source_time, fixed, ok)
ADVANCED = [
    # Source = Fixed
    (ZERO, "parent", VALID, "child", True),
    (ZERO, "other_child", VALID, "child", True),
    (OLD, "parent", VALID, "child", True),
    (OLD, "other_child", VALID, "child", True),
    (VALID, "parent", VALID, "child", True),
    (VALID, "other_child", VALID, "child", True),
    (FUTURE, "parent", VALID, "child", True),
    (FUTURE, "other_child", VALID, "child", True),
    (VALID, "parent", OLD, "child", False),
    (VALID, "other_child", OLD, "child", False),
    (VALID, "parent", FUTURE, "child", False),
    (VALID, "other_child", FUTURE, "child", False),
    # Target = Fixed
    (ZERO, "parent", VALID, "parent", True),
    (OLD, "parent", VALID, "parent", False),
    (VALID, "parent", VALID, "parent", True),
    (FUTURE, "parent", VALID, "parent", False),
    (VALID, "parent", ZERO, "parent", True),
    (VALID, "parent", OLD, "parent", True),
    (VALID, "parent", VALID, "parent", True),
    (VALID, "parent", FUTURE, "parent", True),
]


@pytest.mark.parametrize(("target_time", "source", "source_time", "fixed", "ok"), ADVANCED)
def test_advanced_api_cases(
    target_time: int, source: str, source_time: int, fixed: str, ok: bool
) -> None:
    """test_tf2 buffer_core_test.cpp TEST(tf, canTransform) and TEST(tf, lookupTransform),
    the advanced API: each half short-cuts when its two frames are the same."""
    b = two_link_tree()
    assert b.can_transform_full("child", target_time, source, source_time, fixed) is ok
    if ok:
        b.lookup_transform_full("child", target_time, source, source_time, fixed)
    else:
        with pytest.raises(ExtrapolationException):
            b.lookup_transform_full("child", target_time, source, source_time, fixed)


@pytest.mark.parametrize(
    ("target", "source", "time", "ok"),
    [
        ("child", "parent", VALID, True),
        ("child", "other_child", VALID, True),
        ("child", "parent", ZERO, True),
        ("child", "other_child", ZERO, True),
        ("child", "parent", OLD, False),
        ("child", "other_child", OLD, False),
        ("child", "parent", FUTURE, False),
        ("child", "other_child", FUTURE, False),
    ],
)
def test_basic_api_cases(target: str, source: str, time: int, ok: bool) -> None:
    """test_tf2 buffer_core_test.cpp TEST(tf, canTransform), "Basic API Tests"."""
    b = two_link_tree()
    assert b.can_transform(target, source, time) is ok
    if not ok:
        with pytest.raises(ExtrapolationException):
            b.lookup_transform(target, source, time)


# --- validation texts ----------------------------------------------------------------------


def test_invalid_arguments() -> None:
    """buffer_core_test.cpp TEST(BufferCore_lookupTransform, invalid_arguments) and
    TEST(BufferCore_canTransform, invalid_arguments), with validateFrameId's texts."""
    b = BufferCore()
    b.set_transform(ts("b", "a", 1.0, S))
    b.lookup_transform("b", "a", 0)
    assert b.can_transform("b", "a", 0)
    where = "lookupTransform argument"
    with pytest.raises(InvalidArgumentException) as err:
        b.lookup_transform("", "a", 0)
    assert str(err.value) == (
        f'Invalid argument "" passed to {where} target_frame - in tf2 frame_ids cannot be empty'
    )
    with pytest.raises(InvalidArgumentException):
        b.lookup_transform("b", "", 0)
    with pytest.raises(InvalidArgumentException) as err:
        b.lookup_transform("/b", "a", 0)
    assert str(err.value) == (
        f'Invalid argument "/b" passed to {where} target_frame - in tf2 frame_ids cannot '
        "start with a '/'"
    )
    with pytest.raises(InvalidArgumentException):
        b.lookup_transform("b", "/a", 0)
    for target, source in (("", "a"), ("b", ""), ("/b", "a"), ("b", "/a")):
        assert not b.can_transform(target, source, 0)
    assert b.can_transform("/b", "a", 0, return_debug_tuple=True) == (
        False,
        'Invalid frame ID "/b" passed to canTransform argument target_frame - in tf2 '
        "frame_ids cannot start with a '/'",
    )


def test_lookup_exceptions_of_unknown_frames() -> None:
    """simple_tf2_core.cpp TEST(tf2_lookupTransform, LookupException_Nothing_Exists),
    LookupException_One_Exists, TEST(tf2_canTransform, Nothing_Exists) and One_Exists."""
    b = BufferCore()
    with pytest.raises(LookupException):
        b.lookup_transform("a", "b", S)
    assert not b.can_transform("a", "b", S)
    assert b.set_transform(ts("foo", "child", 0.0, S))
    with pytest.raises(LookupException):
        b.lookup_transform("foo", "bar", S)
    assert not b.can_transform("foo", "bar", S)


def test_backward_forward_and_no_data() -> None:
    """simple_tf2_core.cpp TEST(tf2_lookupTransform, TransformException_Backward_Forward)."""
    b = BufferCore()
    assert b.set_transform(ts("foo", "bar", 0.0, 2 * S))
    b.lookup_transform("foo", "bar", 2 * S)
    with pytest.raises(ExtrapolationException, match=r"but only time 2\.000000 is in the buffer"):
        b.lookup_transform("foo", "bar", 4 * S)
    assert b.set_transform(ts("foo", "bar", 0.0, 3 * S))
    with pytest.raises(ExtrapolationException, match="into the past"):
        b.lookup_transform("foo", "bar", 1 * S)
    with pytest.raises(ExtrapolationException, match="into the future"):
        b.lookup_transform("foo", "bar", 4 * S)


def test_can_transform_core_texts() -> None:
    """tf2_py test_buffer_core.py test_can_transform_core_pass / _fail (the debug tuple)."""
    b = BufferCore()
    b.set_transform(ts("bar", "foo", 2.0, 0))
    b.set_transform(ts("bar", "foo", 2.0, S))
    assert b.can_transform("foo", "bar", S // 2, return_debug_tuple=True) == (True, "")
    b = BufferCore()
    b.set_transform(ts("bar", "foo", 2.0, S))
    b.set_transform(ts("bar", "foo", 2.0, 2 * S))
    ok, why = b.can_transform("foo", "bar", int(2.5 * S), return_debug_tuple=True)
    assert not ok and "extrapolation into the future" in why
    ok, why = b.can_transform("foo", "bar", S // 2, return_debug_tuple=True)
    assert not ok and "extrapolation into the past" in why


# --- latest common time, clear, static/dynamic --------------------------------------------------


def test_get_latest_common_time() -> None:
    """tf2_py test_buffer_core.py test_get_latest_common_time, and tf2_py.cpp's wrapper:
    frames validated as "get_latest_common_time", a failed walk a plain TransformException."""
    b = BufferCore()
    for stamp in (0, S, S // 2):
        b.set_transform(ts("bar", "foo", 2.0, stamp))
    assert b.get_latest_common_time("bar", "foo") == S
    assert b.get_latest_common_time("foo", "foo") == S
    b.set_transform(ts("x", "y", 0.0, S))
    with pytest.raises(TransformException) as err:
        b.get_latest_common_time("bar", "y")
    assert type(err.value) is TransformException
    assert "not part of the same tree" in str(err.value)
    with pytest.raises(LookupException) as lookup_err:
        b.get_latest_common_time("zzz", "zzz")
    assert str(lookup_err.value) == '"zzz" passed to get_latest_common_time does not exist. '


def test_get_latest_common_time_chains() -> None:
    """buffer_core_test.cpp TEST(tf, getLatestCommonTime) (stamps in ns)."""
    b = BufferCore()
    b.set_transform(ts("parent", "a", 0.0, 1000))
    b.set_transform(ts("parent's parent", "parent", 0.0, 2000))
    assert b.get_latest_common_time("a", "parent's parent") == 1000
    b.set_transform(ts("parent", "a", 0.0, 3000))
    assert b.get_latest_common_time("a", "parent's parent") == 2000
    b.set_transform(ts("parent", "b", 0.0, 4000))
    b.set_transform(ts("b", "c", 0.0, 3000))
    b.set_transform(ts("c", "d", 0.0, 9000))
    b.set_transform(ts("f", "e", 0.0, 5000))
    assert b.get_latest_common_time("a", "b") == 3000
    for one, two in (("a", "c"), ("c", "a"), ("a", "d"), ("d", "a")):
        assert b.get_latest_common_time(one, two) == 3000
    assert b.get_latest_common_time("e", "f") == 5000
    assert b.get_latest_common_time("f", "e") == 5000


def test_clear_keeps_frames_and_static_transforms() -> None:
    """tf2_py test_buffer_core.py test_clear; simple_tf2_core.cpp TEST(tf2_clear,
    LookUp_Static_Transfrom_Succeed / _Fail); BufferCore::clear only empties TimeCaches
    (StaticCache::clearList does nothing) and keeps frame ids."""
    b = BufferCore()
    b.set_transform(ts("bar", "foo", 2.0, 0))
    assert b.can_transform("foo", "bar", 0)
    b.clear()
    # a known frame with an empty history: at time 0 the latest-common-time walk stops at it
    # (a connectivity error), at a given time its TimeCache answers "no data"
    ok, why = b.can_transform("foo", "bar", 0, return_debug_tuple=True)
    assert not ok and "not part of the same tree" in why
    ok, why = b.can_transform("foo", "bar", S, return_debug_tuple=True)
    assert not ok
    assert why == (
        "Lookup would require extrapolation at time 1.000000, but only time 0.000000 is in "
        "the buffer, when looking up transform from frame [bar] to frame [foo]"
    )
    assert b.set_transform_static(ts("foo", "bar", 0.0, S))
    b.lookup_transform("foo", "bar", 2 * S)
    b.clear()
    b.lookup_transform("foo", "bar", 2 * S)  # static survives clear


def test_static_and_dynamic_replace_each_other() -> None:
    """buffer_core.cpp setTransformImpl: "Overwrite TimeCacheInterface type with a current
    input": a static insert on a dynamic frame, or a dynamic one on a static frame, starts a
    new cache of the new kind (its history goes)."""
    b = BufferCore()
    b.set_transform(ts("a", "b", 1.0, S))
    b.set_transform_static(ts("a", "b", 2.0, S))
    assert x_of(b.lookup_transform("a", "b", 99 * S)) == 2.0  # static: any time
    b.set_transform(ts("a", "b", 3.0, 5 * S))
    assert x_of(b.lookup_transform("a", "b", 5 * S)) == 3.0
    assert not b.can_transform("a", "b", 99 * S)  # dynamic again: one sample, one time


def test_set_transform_checks() -> None:
    """simple_tf2_core.cpp TEST(tf2, setTransformFail / setTransformValid /
    setTransformInvalidQuaternion); buffer_core_test.cpp BufferCore_setTransform.*."""
    b = BufferCore()
    assert not b.set_transform(msgs.TransformStamped())
    assert b.set_transform(ts("foo", "child", 0.0, S))
    good = ts("foo", "child", 0.0, 2 * S)
    bad = msgs.TransformStamped(
        header=good.header,
        child_frame_id="child",
        transform=msgs.Transform(rotation=msgs.Quaternion(x=0, y=0, z=0, w=0)),
    )
    assert not b.set_transform(bad)
    # one leading '/' goes (stripSlash); a second one stays
    assert b.set_transform(ts("//map", "/odom", 0.0, S))
    assert b.frames()["odom"] == "/map"


def test_refused_old_data_still_names_its_frames() -> None:
    """setTransformImpl numbers child and parent (lookupOrInsertFrameNumber) before
    ``insertData`` can refuse old data, so the parent becomes a known frame."""
    b = BufferCore(cache_time=10.0)
    b.set_transform(ts("b", "a", 0.0, 20 * S))
    assert not b.set_transform(ts("c", "a", 0.0, 1 * S))  # TF_OLD_DATA
    with pytest.raises(ConnectivityException):  # known, unconnected: not a LookupException
        b.lookup_transform("c", "a", 0)


def test_repeated_stamps_and_pruning_as_time_cache() -> None:
    """cache_unittest.cpp TEST(TimeCache, GetAllItems): same stamps keep insertion order
    (newest inserted answers in the middle and at the newest stamp, oldest inserted at the
    oldest stamp), exact repeats are dropped, pruning uses the newest stamp before an insert.
    Stamps are the test's plus 100 ns (time 0 means "latest" to a lookup); storage 10 ns."""
    b = BufferCore(cache_time=10e-9)
    items = [(100, 0), (110, 1), (105, 2), (103, 3), (108, 4), (108, 5), (108, 6)]
    for stamp, ident in items:
        assert b.set_transform(ts("p", "c", float(ident), stamp))
    for stamp, ident in reversed(items):  # exact repeats: accepted, nothing changes
        assert b.set_transform(ts("p", "c", float(ident), stamp))
    assert x_of(b.lookup_transform("p", "c", 100)) == 0.0
    assert x_of(b.lookup_transform("p", "c", 108)) == 6.0  # last inserted of 108
    assert x_of(b.lookup_transform("p", "c", 109)) == pytest.approx(3.5)  # 6 -> 1
    assert b.set_transform(ts("p", "c", 7.0, 115))
    assert x_of(b.lookup_transform("p", "c", 100)) == 0.0  # not pruned yet
    assert not b.set_transform(ts("p", "c", 8.0, 100))  # pruned to >= 105, then refused
    assert b.set_transform(ts("p", "c", 9.0, 105))
    assert not b.can_transform("p", "c", 103)
    assert x_of(b.lookup_transform("p", "c", 105)) == 2.0  # oldest stamp: first inserted
    assert x_of(b.lookup_transform("p", "c", 106)) == pytest.approx(9.0 + (4.0 - 9.0) / 3.0)
    assert x_of(b.lookup_transform("p", "c", 115)) == 7.0


def test_a_loop_is_a_lookup_exception() -> None:
    """walkToTopParent: past MAX_GRAPH_DEPTH it answers TF2_LOOKUP_ERROR with "The tf tree is
    invalid because it contains a loop." and allFramesAsString (frames in first-seen order)."""
    b = BufferCore()
    b.set_transform(ts("b", "a", 0.0, S))
    b.set_transform(ts("a", "b", 0.0, S))
    b.set_transform(ts("z", "c", 0.0, S))
    with pytest.raises(LookupException) as err:
        b.lookup_transform("c", "a", S)
    assert str(err.value) == (
        "The tf tree is invalid because it contains a loop.\n"
        "Frame a exists with parent b.\nFrame b exists with parent a.\n"
        "Frame c exists with parent z.\n\n"
    )
