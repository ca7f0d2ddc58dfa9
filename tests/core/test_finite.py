"""core/finite: NaN and infinity in a message are found by field path, and refused."""

from __future__ import annotations

import math

import pytest

from usar_replay.core import msgs
from usar_replay.core.finite import NonFiniteValue, check_finite, nonfinite_field


def _tf(x: float, child: str = "marker_frame") -> msgs.TransformStamped:
    return msgs.TransformStamped(
        child_frame_id=child,
        transform=msgs.Transform(translation=msgs.Vector3(x=x)),
    )


def test_a_finite_message_has_no_field_named() -> None:
    twist = msgs.Twist(linear=msgs.Vector3(x=0.2), angular=msgs.Vector3(z=-1.0))
    assert nonfinite_field(twist) == ""
    check_finite("/explorer/cmd_vel", twist)  # does not raise
    assert nonfinite_field(msgs.TFMessage(transforms=(_tf(1.0), _tf(2.0)))) == ""


def test_the_first_nonfinite_float_is_named_by_its_dotted_path() -> None:
    assert nonfinite_field(msgs.Twist(angular=msgs.Vector3(z=math.nan))) == "angular.z = nan"
    tf = msgs.TFMessage(transforms=(_tf(1.0), _tf(math.inf), _tf(math.nan)))
    assert nonfinite_field(tf) == "transforms[1].transform.translation.x = inf"


def test_a_tuple_of_floats_names_its_index() -> None:
    cov = (0.0,) * 7 + (-math.inf,) + (0.0,) * 28
    pose = msgs.PoseWithCovariance(covariance=cov)
    assert nonfinite_field(pose) == "covariance[7] = -inf"


def test_check_finite_raises_naming_topic_type_and_field() -> None:
    with pytest.raises(NonFiniteValue) as caught:
        check_finite("/follower/cmd_vel", msgs.Twist(linear=msgs.Vector3(y=math.nan)))
    text = str(caught.value)
    assert text.startswith("/follower/cmd_vel: Twist.linear.y = nan: NaN and infinity")
    assert isinstance(caught.value, ValueError)


def test_strings_and_integers_are_not_checked() -> None:
    log = msgs.Log(name="nan", msg="inf", line=3)
    assert nonfinite_field(log) == ""
