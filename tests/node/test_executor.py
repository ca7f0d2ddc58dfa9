"""node/executor: the callback order of a tick and what a mission may publish or read.

Executor-level tests need no simulator: an :class:`Executor` is made current, nodes are created
in it, and ticks are handed to it by hand, as the mission process does.
"""

from __future__ import annotations

import pytest

from usar_replay.api import (
    Buffer,
    Header,
    Log,
    Node,
    Odometry,
    PoseStamped,
    StaticTransformBroadcaster,
    String,
    TFMessage,
    Time,
    Transform,
    TransformListener,
    TransformStamped,
    Vector3,
)
from usar_replay.core import contract
from usar_replay.node.executor import Executor, PublishPolicy

S = 1_000_000_000
T0 = 100 * S


def _s(text: str) -> String:
    return String(data=text)


def test_timers_fire_before_the_ticks_inputs_earliest_due_first() -> None:
    """In one tick: due timers first (earliest due, then creation order), then the inputs."""
    order: list[str] = []
    ex = Executor()
    with ex.activate():
        node = Node("n")
        node.create_subscription(String, "/in", lambda m: order.append(f"sub:{m.data}"))
        node.create_timer(0.2, lambda: order.append("slow"))
        node.create_timer(0.1, lambda: order.append("fast"))
        node.create_timer(0.2, lambda: order.append("slow2"))
    ex.tick(T0, [("/in", _s("a"))])  # the clock starts: timers are due one period later
    assert order == ["sub:a"]
    order.clear()
    ex.tick(T0 + S // 10, [("/in", _s("b"))])
    assert order == ["fast", "sub:b"]
    order.clear()
    # 0.25 s later: fast was due at 0.2 (and not twice), slow and slow2 at 0.2 too; at equal due
    # times the timer created first fires first
    ex.tick(T0 + S // 4, [("/in", _s("c"))])
    assert order == ["slow", "fast", "slow2", "sub:c"]


def test_subscriptions_run_in_creation_order_across_nodes() -> None:
    order: list[str] = []
    ex = Executor()
    with ex.activate():
        first, second = Node("first"), Node("second")
        second.create_subscription(String, "/x", lambda m: order.append("second.a"))
        first.create_subscription(String, "/x", lambda m: order.append("first.a"))
        second.create_subscription(String, "/x", lambda m: order.append("second.b"))
        first.create_subscription(String, "/y", lambda m: order.append("first.y"))
    ex.tick(T0, [("/y", _s("")), ("/x", _s(""))])
    # inputs in the tick's order; each topic's subscribers in the order they were created
    assert order == ["first.y", "second.a", "first.a", "second.b"]


def test_local_delivery_is_fifo_and_before_the_next_input() -> None:
    """What a callback publishes to a topic of this mission reaches its subscribers right after
    that callback, first published first, before the tick's next input message."""
    order: list[str] = []
    ex = Executor()
    with ex.activate():
        node = Node("n")
        pub_a = node.create_publisher(String, "/a")
        pub_b = node.create_publisher(String, "/b")
        pub_c = node.create_publisher(String, "/c")

        def on_in(m: String) -> None:
            order.append(f"in:{m.data}")
            if m.data == "1":
                pub_a.publish(_s("a"))
                pub_b.publish(_s("b"))

        def on_a(m: String) -> None:
            order.append("a")
            pub_c.publish(_s("c"))  # queued after b, which was published first

        node.create_subscription(String, "/in", on_in)
        node.create_subscription(String, "/a", on_a)
        node.create_subscription(String, "/b", lambda m: order.append("b"))
        node.create_subscription(String, "/c", lambda m: order.append("c"))
    out = ex.tick(T0, [("/in", _s("1")), ("/in", _s("2"))])
    assert order == ["in:1", "a", "b", "c", "in:2"]
    # everything published is the tick's output, in publish order
    assert [(t, m.data) for t, m in out if isinstance(m, String)] == [
        ("/a", "a"),
        ("/b", "b"),
        ("/c", "c"),
    ]


def test_what_constructors_publish_is_the_first_ticks_output_in_creation_order() -> None:
    """A logger line, a static transform and a publish made in ``__init__`` are not lost: they
    open the first tick's output, in the order they were made, and reach the mission's own
    subscribers (a later node's TransformListener included) before that tick's timers and
    inputs, as rclpy delivers them."""
    order: list[str] = []
    ex = Executor()
    with ex.activate():
        first = Node("first")
        first.get_logger().info("first is up")
        StaticTransformBroadcaster(first).sendTransform(
            TransformStamped(
                header=Header(frame_id="map"),
                child_frame_id="landmark",
                transform=Transform(translation=Vector3(x=2.0)),
            )
        )
        second = Node("second")
        buffer = Buffer()
        TransformListener(buffer, second)  # created after the broadcast: still gets it
        second.create_subscription(String, "/hello", lambda m: order.append(f"hello:{m.data}"))
        second.create_subscription(String, "/in", lambda m: order.append(f"in:{m.data}"))
        second.create_timer(0.05, lambda: order.append("timer"))
        second.create_publisher(String, "/hello").publish(_s("from __init__"))
        second.get_logger().warning("second is up")
    assert order == []  # nothing runs before the first tick
    out = ex.tick(T0, [("/in", _s("1"))])
    assert [(topic, type(m).__name__) for topic, m in out] == [
        (contract.ROSOUT, "Log"),
        (contract.TF_STATIC, "TFMessage"),
        ("/hello", "String"),
        (contract.ROSOUT, "Log"),
    ]
    logs = [m for _, m in out if isinstance(m, Log)]
    assert [(m.name, m.msg) for m in logs] == [("first", "first is up"), ("second", "second is up")]
    assert order == ["hello:from __init__", "in:1"]  # before the tick's input
    found = buffer.lookup_transform("map", "landmark", Time())
    assert found.transform.translation.x == 2.0
    # delivered once: the next tick's output does not repeat them
    assert ex.tick(T0 + S // 10, [("/in", _s("2"))]) == []
    assert order[-2:] == ["timer", "in:2"]


@pytest.mark.parametrize(
    ("topic", "msg_type"),
    [
        (contract.truth_pose("explorer"), PoseStamped),
        (contract.TRUTH_MARKERS, TFMessage),
        (contract.odom("explorer"), Odometry),
        (contract.IMAGE, String),
    ],
)
def test_publishing_ground_truth_or_the_simulators_topics_is_refused(
    topic: str, msg_type: type
) -> None:
    ex = Executor(policy=PublishPolicy(sim_frames=contract.sim_frames()))
    with ex.activate():
        node = Node("n")
        with pytest.raises(PermissionError, match=topic):
            node.create_publisher(msg_type, topic)


def test_reading_ground_truth_is_refused() -> None:
    ex = Executor()
    with ex.activate():
        node = Node("n")
        with pytest.raises(PermissionError, match="ground truth"):
            node.create_subscription(PoseStamped, contract.truth_pose("follower"), print)


def test_broadcasting_the_simulators_tf_links_is_refused() -> None:
    """/tf is open to missions, but not the links the simulator owns (base, odom, camera)."""
    ex = Executor(policy=PublishPolicy(sim_frames=contract.sim_frames()))
    with ex.activate():
        node = Node("n")
        tf = node.create_publisher(TFMessage, contract.TF)
        mine = TransformStamped(child_frame_id=contract.MARKER_FRAME)
        tf.publish(TFMessage(transforms=(mine,)))  # allowed
        theirs = TransformStamped(child_frame_id=contract.base_frame("explorer"))
        with pytest.raises(PermissionError, match="simulator publishes the tf link"):
            tf.publish(TFMessage(transforms=(mine, theirs)))
        with pytest.raises(PermissionError, match="simulator"):
            ex.publish(contract.TF_STATIC, TFMessage(transforms=(theirs,)))
