"""The generated CDR decoders (:mod:`usar_replay.core.cdrdecode`) against rosbags, the reference.

Why: the generated decoders are what grade and replay see, so they must give exactly rosbags'
values (same classes, same field types, same float bits) for every type, and must never accept
bytes that rosbags rejects. Values are compared strictly: ``==`` alone would take ``1`` for
``True`` and would fail on NaN.
"""

from __future__ import annotations

import dataclasses
import struct
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from msg_strategies import message

from usar_replay.core import cdr, cdrdecode, msgs


def _same(a: Any, b: Any) -> bool:
    """Equal, of the same types all the way down, floats bit for bit."""
    if type(a) is not type(b):
        return False
    if isinstance(a, float):
        return struct.pack("<d", a) == struct.pack("<d", b)
    if isinstance(a, tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, msgs.Message):
        return all(_same(getattr(a, f.name), getattr(b, f.name)) for f in dataclasses.fields(a))
    return bool(a == b)


def _fast(cls: type[msgs.Message]) -> cdrdecode.Decoder:
    fn = cdrdecode.decoder(cls)
    assert fn is not None, f"{cls.__name__} has no generated decoder"
    return fn


def test_the_comparison_is_strict() -> None:
    assert not _same(msgs.RegionOfInterest(do_rectify=True), msgs.RegionOfInterest(do_rectify=1))  # type: ignore[arg-type]
    assert _same(msgs.Vector3(x=float("nan")), msgs.Vector3(x=float("nan")))
    assert not _same(msgs.Vector3(x=0.0), msgs.Vector3(x=-0.0))
    assert not _same(msgs.CompressedImage(data=b"a"), msgs.CompressedImage(data=b"b"))


@pytest.mark.parametrize("cls", msgs.MESSAGE_TYPES, ids=lambda c: c.__name__)
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_generated_decoder_equals_rosbags(cls: type[msgs.Message], data: st.DataObject) -> None:
    """Every type has a generated decoder, and it decodes rosbags' bytes to rosbags' value."""
    value = data.draw(message(cls))
    raw = cdr.encode(value)
    got = _fast(cls)(raw)
    assert _same(got, cdr.decode_reference(raw, cls.__msgtype__))
    assert _same(got, value)
    assert _same(cdr.decode(raw, cls.__msgtype__), got)


@pytest.mark.parametrize("cls", msgs.MESSAGE_TYPES, ids=lambda c: c.__name__)
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_damaged_bytes_decode_as_rosbags_decodes_them(
    cls: type[msgs.Message], data: st.DataObject
) -> None:
    """Random changes to valid bytes (flipped bytes: odd floats, NaN payloads, wrong lengths;
    cut or padded ends): the generated decoder either declines (:class:`Unsupported`) or gives
    rosbags' value; it never accepts what rosbags rejects. ``cdr.decode`` then gives rosbags'
    value or rosbags' error."""
    raw = bytearray(cdr.encode(data.draw(message(cls))))
    for _ in range(data.draw(st.integers(0, 4))):
        i = data.draw(st.integers(0, len(raw) - 1))
        raw[i] = data.draw(st.integers(0, 255))
    cut = data.draw(st.integers(-8, 8))
    damaged = bytes(raw[:cut] if cut < 0 else raw + bytes(cut))
    try:
        ref: msgs.Message | None = cdr.decode_reference(damaged, cls.__msgtype__)
        ref_err = ""
    except Exception as err:  # noqa: BLE001 - any error rosbags raises is the reference
        ref, ref_err = None, f"{type(err).__name__}: {err}"
    try:
        got: msgs.Message | None = _fast(cls)(damaged)
    except cdrdecode.Unsupported:
        got = None
    except Exception:  # noqa: BLE001 - struct.error, UnicodeDecodeError: declined too
        got = None
    if got is not None:
        assert ref is not None, f"accepted bytes rosbags rejects ({ref_err})"
        assert _same(got, ref)
    try:
        public: msgs.Message | None = cdr.decode(damaged, cls.__msgtype__)
        err = ""
    except Exception as e:  # noqa: BLE001
        public, err = None, f"{type(e).__name__}: {e}"
    assert err == ref_err
    if ref is not None:
        assert _same(public, ref)


def test_nan_and_signed_zero_keep_their_bits() -> None:
    payload_nan = struct.unpack("<d", b"\x01\x00\x00\x00\x00\x00\xf8\x7f")[0]
    weird = (float("nan"), -0.0, float("inf"), payload_nan)
    value = msgs.Odometry(
        child_frame_id="base",
        pose=msgs.PoseWithCovariance(covariance=weird * 9),
        twist=msgs.TwistWithCovariance(twist=msgs.Twist(linear=msgs.Vector3(x=-0.0, y=weird[3]))),
    )
    raw = cdr.encode(value)
    assert _same(_fast(msgs.Odometry)(raw), cdr.decode_reference(raw, msgs.Odometry.__msgtype__))
    grid = msgs.OccupancyGrid(info=msgs.MapMetaData(resolution=float("nan")), data=b"\x00\xff")
    raw = cdr.encode(grid)
    assert _same(_fast(msgs.OccupancyGrid)(raw), cdr.decode_reference(raw, grid.__msgtype__))


def test_big_endian_goes_to_rosbags() -> None:
    value = msgs.TFMessage(
        transforms=(msgs.TransformStamped(child_frame_id="a", transform=msgs.Transform()),)
    )
    ros = cdr._to_ros_fn(msgs.TFMessage)(value)
    raw = bytes(cdr.typestore().serialize_cdr(ros, value.__msgtype__, little_endian=False))
    assert raw[:2] == b"\x00\x00"
    with pytest.raises(cdrdecode.Unsupported):
        _fast(msgs.TFMessage)(raw)
    assert _same(cdr.decode(raw, value.__msgtype__), value)


def test_a_buffer_that_is_not_bytes_still_gives_bytes_fields() -> None:
    value = msgs.CompressedImage(format="png", data=b"\x89PNG")
    got = cdr.decode(memoryview(cdr.encode(value)), value.__msgtype__)  # type: ignore[arg-type]
    assert _same(got, value)


def test_an_unknown_type_is_a_key_error() -> None:
    with pytest.raises(KeyError):
        cdr.decode(b"\x00\x01\x00\x00", "nope_msgs/msg/Nope")


def test_definitions_are_read_as_the_typestore_reads_them() -> None:
    """The field list the generator reads from ``__msgdef__`` is rosbags' parse of it."""
    store = cdr.typestore()
    for cls in msgs.MESSAGE_TYPES:
        _, fielddefs = store.fielddefs[cls.__msgtype__]
        ours = cdrdecode._fields(cls)
        assert [name for name, _ in fielddefs] == [name for name, _, _ in ours]
        for (_, (node, detail)), (_, typ, length) in zip(fielddefs, ours, strict=True):
            if length is None:
                assert (detail[0] if node.name == "BASE" else detail) == typ
            else:
                (_, inner), n = detail
                assert (inner[0] if isinstance(inner, tuple) else inner) == typ
                assert n == (length if length >= 0 else 0)
