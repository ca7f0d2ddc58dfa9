"""core/cdr: every message type to CDR bytes and back, the bytes the log and the mission
process share; rosbags decides where the generated decoders do not."""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from msg_strategies import message

from usar_replay.core import cdr, msgs


def test_schema_text_is_ros2_form() -> None:
    text = cdr.schema_text("sensor_msgs/msg/CompressedImage")
    assert "builtin_interfaces/Time stamp" in text
    assert "MSG: std_msgs/Header" in text


@pytest.mark.parametrize("cls", msgs.MESSAGE_TYPES, ids=lambda c: c.__msgtype__)
@settings(max_examples=40, suppress_health_check=[HealthCheck.too_slow], deadline=None)
@given(data=st.data())
def test_cdr_round_trip(cls: type[msgs.Message], data: st.DataObject) -> None:
    value = data.draw(message(cls))
    raw = cdr.encode(value)
    back = cdr.decode(raw, cls.__msgtype__)
    assert back == value
    assert cdr.encode(back) == raw


def test_encode_is_deterministic_and_sensitive() -> None:
    a = msgs.Twist(linear=msgs.Vector3(x=0.1))
    b = msgs.Twist(linear=msgs.Vector3(x=0.1000000001))
    assert cdr.encode(a) == cdr.encode(msgs.Twist(linear=msgs.Vector3(x=0.1)))
    assert cdr.encode(a) != cdr.encode(b)


def test_bytes_that_are_not_a_message_fail_as_rosbags_fails() -> None:
    raw = cdr.encode(msgs.String(data="hello"))
    with pytest.raises(Exception) as fast:
        cdr.decode(raw[:6], msgs.String.__msgtype__)
    with pytest.raises(Exception) as reference:
        cdr.decode_reference(raw[:6], msgs.String.__msgtype__)
    assert type(fast.value) is type(reference.value)


def test_the_typestore_holds_exactly_usars_types() -> None:
    names = set(cdr.typestore().fielddefs)
    assert {cls.__msgtype__ for cls in msgs.MESSAGE_TYPES} <= names
    assert "sensor_msgs/msg/Image" not in names  # an empty store plus ours, not a distro's
