"""node/boundary_check: the recorder's gate on what a mission process sends back, fed real CDR
bytes (a modified mission process can send anything)."""

from __future__ import annotations

import math

import pytest

from usar_replay.core import cdr, contract, msgs
from usar_replay.node.boundary_check import (
    MAX_TICK_MESSAGES,
    MAX_TOPICS,
    BoundaryCheck,
    OutputRefused,
    transforms_problem,
)
from usar_replay.node.executor import PublishPolicy

TWIST = msgs.Twist.__msgtype__


def _check() -> BoundaryCheck:
    # the US&R world's: the simulator's topics and frames, and the course's trusted detector
    sim_topics = (*contract.SIM_TOPICS, contract.FIDUCIALS)
    return BoundaryCheck(PublishPolicy(sim_topics=sim_topics, sim_frames=contract.sim_frames()))


def _item(topic: str, value: msgs.Message) -> tuple[str, str, bytes]:
    return (topic, type(value).__msgtype__, cdr.encode(value))


def test_the_recorder_refuses_too_many_transforms_whatever_the_mission_process_says() -> None:
    from usar_replay.core import cdr, msgs
    from usar_replay.node.boundary_check import BoundaryCheck, OutputRefused
    from usar_replay.node.executor import PublishPolicy

    check = BoundaryCheck(PublishPolicy(sim_topics=(), sim_frames=()))
    one = msgs.TransformStamped(
        header=msgs.Header(frame_id="explorer_tf/camera_link"), child_frame_id="marker_frame"
    )
    tf = msgs.TFMessage.__msgtype__
    ok = cdr.encode(msgs.TFMessage(transforms=(one,) * 1000))
    assert len(check.check([("/tf", tf, ok)] * 10)) == 10  # 1,000 a message, 10,000 a tick
    with pytest.raises(OutputRefused, match="1001 transforms"):
        check.check([("/tf", tf, cdr.encode(msgs.TFMessage(transforms=(one,) * 1001)))])
    with pytest.raises(OutputRefused, match="11000 transforms in one tick"):
        check.check([("/tf", tf, ok)] * 11)


def test_an_honest_tick_comes_back_decoded() -> None:
    twist = msgs.Twist(linear=msgs.Vector3(x=0.2))
    log = msgs.Log(name="explorer", msg="hi")
    got = _check().check([_item("/explorer/cmd_vel", twist), _item(contract.ROSOUT, log)])
    assert [(t, v) for t, _, _, v in got] == [("/explorer/cmd_vel", twist), (contract.ROSOUT, log)]


@pytest.mark.parametrize(
    ("item", "why"),
    [
        (("/x", "nope_msgs/msg/Nope", b""), "published type 'nope_msgs/msg/Nope' on /x: unknown"),
        (("/x", TWIST, b"\x00\x01\x00\x00\x01"), "bytes on /x that do not decode as"),
        (("/" + "t" * 300, TWIST, b""), "is over 256 characters"),
        (_item("/explorer/cmd_vel", msgs.Log()), "/explorer/cmd_vel carries geometry_msgs/msg/Tw"),
        (_item("/x", msgs.Twist(linear=msgs.Vector3(x=math.nan))), "Twist.linear.x = nan: NaN"),
        (_item("/ground_truth/explorer/pose", msgs.PoseStamped()), "is ground truth"),
        (_item(contract.IMAGE, msgs.CompressedImage()), "is published by the simulator"),
        (_item(contract.FIDUCIALS, msgs.FiducialTransformArray()), "course's detector's output"),
        (_item(contract.COURSE_VIEW_IMAGE, msgs.CompressedImage()), "is the recorder's"),
        (
            _item(
                contract.TF,
                msgs.TFMessage(
                    transforms=(msgs.TransformStamped(child_frame_id="explorer_tf/odom"),)
                ),
            ),
            "the simulator publishes the tf link to explorer_tf/odom",
        ),
    ],
)
def test_what_is_refused_says_what_and_where(item: tuple[str, str, bytes], why: str) -> None:
    with pytest.raises(OutputRefused) as caught:
        _check().check([item])
    assert why in str(caught.value)


def test_one_topic_keeps_one_type_across_ticks_and_topics_are_counted() -> None:
    check = _check()
    check.check([_item("/mine", msgs.String(data="a"))])
    with pytest.raises(OutputRefused, match="/mine carries std_msgs/msg/String"):
        check.check([_item("/mine", msgs.Bool())])
    check.check([_item(f"/t{i}", msgs.Bool()) for i in range(MAX_TOPICS - 1)])
    with pytest.raises(OutputRefused, match=f"more than {MAX_TOPICS} topics"):
        check.check([_item("/one_more", msgs.Bool())])


def test_a_flood_of_messages_in_one_tick_is_refused_before_decoding() -> None:
    items = [("/x", "nope_msgs/msg/Nope", b"")] * (MAX_TICK_MESSAGES + 1)
    with pytest.raises(OutputRefused, match=f"{MAX_TICK_MESSAGES + 1} messages in one tick"):
        _check().check(items)


def test_transforms_problem_counts_detections_too() -> None:
    many = msgs.FiducialTransformArray(transforms=(msgs.FiducialTransform(),) * 1001)
    assert "a FiducialTransformArray with 1001 transforms" in transforms_problem("/d", many)
    assert transforms_problem("/d", msgs.FiducialTransformArray()) == ""
    assert transforms_problem("/d", msgs.Twist()) == ""
