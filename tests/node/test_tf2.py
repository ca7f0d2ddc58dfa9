"""node/tf2: tf2_ros's Python shapes over usar's buffer: broadcasters that publish, a listener
that subscribes, lookups with rclpy-style times. An executor is made current and ticks are
handed to it by hand, as the mission process does."""

from __future__ import annotations

import pytest

from usar_replay.core import contract, msgs
from usar_replay.node.executor import Executor
from usar_replay.node.node import Duration, Node, Time
from usar_replay.node.tf2 import (
    Buffer,
    ExtrapolationException,
    LookupException,
    StaticTransformBroadcaster,
    TransformBroadcaster,
    TransformListener,
)

S = 1_000_000_000


def _tf(parent: str, child: str, x: float, t_ns: int) -> msgs.TransformStamped:
    return msgs.TransformStamped(
        header=msgs.Header(stamp=msgs.Time.from_ns(t_ns), frame_id=parent),
        child_frame_id=child,
        transform=msgs.Transform(translation=msgs.Vector3(x=x)),
    )


def test_broadcasters_publish_one_message_per_call_on_their_topic() -> None:
    ex = Executor()
    with ex.activate():
        node = Node("b")
        dynamic, static = TransformBroadcaster(node), StaticTransformBroadcaster(node)

        def on_go(_: msgs.String) -> None:
            dynamic.sendTransform([_tf("map", "a", 1.0, S), _tf("a", "b", 2.0, S)])
            static.send_transform(_tf("map", "origin1", 3.0, 0))

        node.create_subscription(msgs.String, "/go", on_go)
    out = ex.tick(S, [("/go", msgs.String())])
    assert [(topic, len(m.transforms)) for topic, m in out if isinstance(m, msgs.TFMessage)] == [
        (contract.TF, 2),
        (contract.TF_STATIC, 1),
    ]


def test_a_listener_fills_its_buffer_from_the_ticks_inputs() -> None:
    ex = Executor()
    with ex.activate():
        node = Node("listener")
        buffer = Buffer(cache_time=Duration.from_seconds(5.0), node=node)
        TransformListener(buffer, node)
    assert not buffer.can_transform("map", "b", Time())
    ex.tick(
        S,
        [
            (contract.TF_STATIC, msgs.TFMessage(transforms=(_tf("map", "a", 1.0, 0),))),
            (contract.TF, msgs.TFMessage(transforms=(_tf("a", "b", 2.0, S),))),
        ],
    )
    ex.tick(2 * S, [(contract.TF, msgs.TFMessage(transforms=(_tf("a", "b", 4.0, 2 * S),)))])
    latest = buffer.lookup_transform("map", "b", Time())  # zero: the latest common time
    assert latest.transform.translation.x == 5.0 and latest.header.stamp.ns == 2 * S
    halfway = buffer.lookup_transform("map", "b", msgs.Time.from_ns(3 * S // 2))
    assert halfway.transform.translation.x == pytest.approx(4.0)  # interpolated
    assert buffer.lookup_transform("map", "b", Time(S)).transform.translation.x == 3.0
    assert buffer.can_transform("map", "b", 2 * S, timeout=Duration.from_seconds(1))
    with pytest.raises(ExtrapolationException):
        buffer.lookup_transform("map", "b", Time(3 * S))  # no waiting: now or never
    with pytest.raises(LookupException):
        buffer.lookup_transform("map", "nowhere", Time())


def test_the_buffer_keeps_its_cache_time() -> None:
    assert Buffer().cache_time_ns == 10 * S
    assert Buffer(cache_time=Duration.from_seconds(2.5)).cache_time_ns == 2_500_000_000
    assert Buffer(cache_time=30.0).cache_time_ns == 30 * S
