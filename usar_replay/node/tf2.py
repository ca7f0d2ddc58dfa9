"""tf2_ros's Python API bound to a :class:`usar_replay.node.node.Node`.

Why a layer over :mod:`usar_replay.core.tf_tree`: the buffer there is tf2's ``BufferCore`` (pure,
exact, tested against tf2); mission code expects tf2_ros's shapes: a ``TransformListener(buffer,
node)`` that subscribes to ``/tf`` and ``/tf_static``, a ``TransformBroadcaster(node)`` whose
``sendTransform`` publishes, and lookups that take ``rclpy``-style times. tf2's exceptions
(``LookupException``, ``ExtrapolationException``, ``ConnectivityException``) reach your code
exactly as tf2 raises them; there is no waiting (``timeout`` is accepted and ignored): the data
of a replay is the log, so a lookup succeeds now or never for this tick.
"""

from __future__ import annotations

from collections.abc import Sequence

from usar_replay.core import contract, msgs, tf_tree
from usar_replay.core.tf_tree import (
    ConnectivityException,
    ExtrapolationException,
    InvalidArgumentException,
    LookupException,
    TimeoutException,
    TransformException,
)
from usar_replay.node.node import Duration, Node, Time

__all__ = [
    "Buffer",
    "ConnectivityException",
    "ExtrapolationException",
    "InvalidArgumentException",
    "LookupException",
    "StaticTransformBroadcaster",
    "TimeoutException",
    "TransformBroadcaster",
    "TransformException",
    "TransformListener",
]

TimeLike = Time | msgs.Time | int


def _ns(time: TimeLike) -> int:
    if isinstance(time, Time):
        return time.nanoseconds
    if isinstance(time, msgs.Time):
        return time.ns
    return int(time)


class Buffer(tf_tree.BufferCore):
    """tf2_ros.Buffer: ``lookup_transform(target, source, time)`` with ``Time()`` meaning the
    latest common time, as in tf2."""

    def __init__(self, cache_time: Duration | float | None = None, node: Node | None = None):
        if isinstance(cache_time, Duration):
            seconds = cache_time.nanoseconds / 1e9
        else:
            seconds = 10.0 if cache_time is None else float(cache_time)
        super().__init__(cache_time=seconds)

    def lookup_transform(
        self,
        target_frame: str,
        source_frame: str,
        time: TimeLike,
        timeout: Duration | None = None,
    ) -> msgs.TransformStamped:
        return super().lookup_transform(target_frame, source_frame, _ns(time))

    def can_transform(  # type: ignore[override]
        self,
        target_frame: str,
        source_frame: str,
        time: TimeLike,
        timeout: Duration | None = None,
    ) -> bool:
        return super().can_transform(target_frame, source_frame, _ns(time))


class TransformListener:
    """tf2_ros.TransformListener: fills ``buffer`` from ``/tf`` and ``/tf_static``.

    Its subscriptions are created when it is, so a node that builds its listener first has its
    buffer filled before its own ``/tf`` callbacks run (the executor's creation order).
    """

    def __init__(self, buffer: tf_tree.BufferCore, node: Node, *, spin_thread: bool = False):
        self.buffer = buffer
        self.node = node
        self._core = tf_tree.BufferFeeder(buffer, authority=node.get_name())
        node.create_subscription(msgs.TFMessage, contract.TF, self._core.on_tf)
        node.create_subscription(msgs.TFMessage, contract.TF_STATIC, self._core.on_tf_static)


class TransformBroadcaster:
    """tf2_ros.TransformBroadcaster: ``sendTransform(t)`` publishes ``t`` on ``/tf``."""

    topic = contract.TF

    def __init__(self, node: Node, qos: object = 100):
        self._pub = node.create_publisher(msgs.TFMessage, self.topic)

    def sendTransform(
        self, transform: msgs.TransformStamped | Sequence[msgs.TransformStamped]
    ) -> None:
        items = (transform,) if isinstance(transform, msgs.TransformStamped) else tuple(transform)
        self._pub.publish(msgs.TFMessage(transforms=items))

    send_transform = sendTransform


class StaticTransformBroadcaster(TransformBroadcaster):
    """tf2_ros.StaticTransformBroadcaster: the same on ``/tf_static`` (latched)."""

    topic = contract.TF_STATIC
