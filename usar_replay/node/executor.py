"""The deterministic executor: runs a mission's nodes one callback at a time, in a fixed order.

Why this order is the product: replay promises that the same inputs give the same outputs, byte
for byte. A ROS executor interleaves callbacks by thread timing; this one has no threads and no
clock of its own. The simulator (live) or the log (replay) hands it one *tick* at a time: a sim
time and the messages the simulator published then, in the simulator's order
(:data:`usar_replay.core.contract.SIM_TOPICS`). For each tick:

1. the clock moves to the tick's time (``node.get_clock().now()``);
2. at the first tick only: what the nodes published while they were being created (a logger
   line, a ``StaticTransformBroadcaster.sendTransform``, a ``publish`` in ``__init__``) is
   delivered, in the order it was published, to the subscriptions that exist by then (created
   before or after the publish), and opens the first tick's output; so a static transform
   sent in a constructor reaches every ``TransformListener`` before any callback runs, as
   ``/tf_static``'s latching makes it in ROS. Before the first tick the clock reads 0, as
   rclpy's sim clock does before ``/clock`` arrives, so such messages are stamped 0;
3. every timer due at or before that time fires once, earliest due first, ties in the order
   the timers were created;
4. each input message goes to the subscriptions on its topic in the order they were created
   (nodes in creation order, each node's subscriptions in creation order);
5. whatever a callback publishes on a topic that a node of this mission subscribes to is
   delivered right after that callback returns, before the next message, first published first
   (ROS's intra-process delivery, made deterministic); so a ``TransformBroadcaster`` feeds the
   node's own ``TransformListener`` before the next input;
6. everything published during the tick is the tick's output, in publish order: it is written
   to the log at the tick's sim time and, live, ``cmd_vel`` goes to the simulator before the
   next physics step.

Nothing here reads a wall clock, a random generator or a thread: a mission whose own code does
neither is deterministic, and ``usar replay`` proves it.
"""

from __future__ import annotations

import contextlib
from collections import deque
from collections.abc import Iterable, Iterator, Mapping, Sequence
from typing import Any

from usar_replay.core import contract, msgs
from usar_replay.core.finite import check_finite
from usar_replay.node.boundary_check import (
    MAX_TICK_MESSAGES,
    OutputRefused,
    PublishRefused,
    transforms_problem,
)
from usar_replay.node.node import (
    Node,
    Subscription,
    Timer,
    current_executor,
    reset_current_executor,
    set_current_executor,
)

__all__ = ["MAX_LOCAL_DELIVERIES", "Executor", "PublishPolicy", "shutdown"]

MAX_LOCAL_DELIVERIES = 100_000
"""Messages a mission may deliver to itself within one tick before it is stopped (a callback
that publishes to its own topic forever would otherwise hang the run)."""

Output = tuple[str, msgs.Message]


class PublishPolicy:
    """What a mission may publish: not ground truth, not the simulator's topics, not the
    simulator's tf links. The mission process checks it for a clear error at the call; the
    recorder checks it again on what comes out of the process (the security boundary)."""

    def __init__(
        self,
        sim_topics: Sequence[str] = contract.SIM_TOPICS,
        sim_frames: Sequence[str] = (),
    ) -> None:
        # /tf and /tf_static are shared (a mission broadcasts its own frames); the simulator's
        # links on them are protected by sim_frames
        self.sim_topics = frozenset(sim_topics) - {contract.TF, contract.TF_STATIC}
        self.sim_frames = frozenset(sim_frames)

    def topic_problem(self, topic: str) -> str:
        """Why ``topic`` may not be published (empty when it may)."""
        if contract.is_ground_truth(topic):
            return f"{topic} is ground truth: a mission can neither read nor publish it"
        if topic in (contract.FIDUCIALS, contract.ARUCO_MARKERS) and topic in self.sim_topics:
            return (
                f"{topic} is the course's detector's output (trusted, run by usar); a mission "
                "may not publish it: publish your own detector's results on a topic of your own"
            )
        if topic in self.sim_topics:
            return f"{topic} is published by the simulator; a mission may not publish it"
        if topic in contract.COURSE_VIEW_TOPICS:
            return (
                f"{topic} is the recorder's (the course camera's region its detector searched); "
                "a mission may not publish it"
            )
        if not topic.startswith("/"):
            return f"{topic!r} is not an absolute topic name (it must start with '/')"
        return ""

    def own_topic(self, topic: str) -> str:
        """Where the mission's messages on ``topic`` go: the trusted detections the world
        provides (the ROS 2 final project's ``/aruco_markers``) are renamed to the mission's
        own copy (:data:`~usar_replay.core.contract.MISSION_COPIES`), as ROS remaps a topic;
        any other topic is itself. The recorder never renames: a mission that sends the
        trusted name past the node API is refused (:meth:`topic_problem`)."""
        if topic in self.sim_topics:
            return contract.MISSION_COPIES.get(topic, topic)
        return topic

    def message_problem(self, topic: str, msg: msgs.Message) -> str:
        """Why this message may not be published (empty when it may)."""
        problem = self.topic_problem(topic)
        if problem:
            return problem
        if topic in (contract.TF, contract.TF_STATIC) and isinstance(msg, msgs.TFMessage):
            for t in msg.transforms:
                if t.child_frame_id.lstrip("/") in self.sim_frames:
                    return (
                        f"the simulator publishes the tf link to {t.child_frame_id}; a mission "
                        "may not broadcast it"
                    )
        return ""


class Executor:
    """Runs the nodes of one mission process (see the module docstring for the order)."""

    def __init__(
        self,
        parameters: Mapping[str, Any] | None = None,
        policy: PublishPolicy | None = None,
    ) -> None:
        self.parameters: dict[str, Any] = dict(sorted((parameters or {}).items()))
        self.policy = policy or PublishPolicy()
        self.now_ns = 0
        self.nodes: list[Node] = []
        self._subs: dict[str, list[Subscription]] = {}
        self._timers: list[Timer] = []
        self._queue: deque[Output] = deque()
        self._outputs: list[Output] = []
        self._local = 0
        self.shutdown_requested = False
        self.shutdown_reason = ""
        self._started = False

    @contextlib.contextmanager
    def activate(self) -> Iterator[Executor]:
        """Make this the executor new nodes join (the mission process does it around main)."""
        token = set_current_executor(self)
        try:
            yield self
        finally:
            reset_current_executor(token)

    # -- registration (called by Node) ---------------------------------------------------------

    def add_node(self, node: Node) -> None:
        self.nodes.append(node)

    def remove_node(self, node: Node) -> None:
        for subs in self._subs.values():
            subs[:] = [s for s in subs if s.node is not node]
        for t in self._timers:
            if t.node is node:
                t.cancel()
        if node in self.nodes:
            self.nodes.remove(node)

    def add_subscription(self, sub: Subscription) -> None:
        if contract.is_ground_truth(sub.topic_name):
            raise PublishRefused(
                f"{sub.topic_name} is ground truth: it is for the grader, never for a mission"
            )
        self._subs.setdefault(sub.topic_name, []).append(sub)

    def add_timer(self, timer: Timer) -> None:
        self._timers.append(timer)

    def subscription_count(self, topic: str) -> int:
        return len(self._subs.get(topic, ()))

    def provided_by_world(self, topic: str) -> bool:
        """Whether the world publishes ``topic`` to this mission (the simulator's topics, the
        course's trusted ``/fiducial_transforms`` or ``/aruco_markers``): a node that would
        publish it stays idle."""
        return topic in self.policy.sim_topics

    def check_publish_topic(self, topic: str) -> None:
        problem = self.policy.topic_problem(self.policy.own_topic(topic))
        if problem:
            raise PublishRefused(problem)

    # -- publishing ----------------------------------------------------------------------------

    def publish(self, topic: str, msg: msgs.Message) -> None:
        """Queue ``msg`` as an output of this tick, and for local subscribers.

        Refused at the call, with the error where the user published: a topic the mission may
        not publish (``PermissionError``), NaN or infinity in any field
        (:class:`~usar_replay.core.finite.NonFiniteValue`, a ``ValueError`` naming the field),
        more than :data:`~usar_replay.node.boundary_check.MAX_TICK_MESSAGES` messages in one
        tick or more than :data:`~usar_replay.node.boundary_check.MAX_MESSAGE_TRANSFORMS`
        transforms in one message (:class:`~usar_replay.node.boundary_check.OutputRefused`).
        The recorder checks all of it again on its side. On a trusted topic the world provides,
        the message is the mission's own copy (:meth:`PublishPolicy.own_topic`)."""
        topic = self.policy.own_topic(topic)
        problem = self.policy.message_problem(topic, msg)
        if problem:
            raise PublishRefused(problem)
        check_finite(topic, msg)
        too_many = transforms_problem(topic, msg)  # a tf with thousands of frames
        if too_many:
            raise OutputRefused(too_many)
        if len(self._outputs) >= MAX_TICK_MESSAGES:
            raise OutputRefused(
                f"{topic}: more than {MAX_TICK_MESSAGES} messages published in one tick"
            )
        self._outputs.append((topic, msg))
        if topic in self._subs:
            self._queue.append((topic, msg))

    def log(self, name: str, level: int, text: str) -> None:
        """A logger line, published on ``/rosout`` at the current sim time."""
        self.publish(
            contract.ROSOUT,
            msgs.Log(stamp=msgs.Time.from_ns(self.now_ns), level=level, name=name, msg=text),
        )

    def request_shutdown(self, reason: str = "") -> None:
        """The mission says it is done (``usar_replay.api.shutdown()``): the run ends after
        this tick."""
        self.shutdown_requested = True
        self.shutdown_reason = reason

    # -- running ---------------------------------------------------------------------------------

    def tick(self, t_ns: int, inputs: Iterable[Output]) -> list[Output]:
        """Run one simulator tick (see the module docstring); returns what was published.

        ``inputs`` is iterated once, in order, each message taken just before it is delivered
        (the mission process decodes them lazily there, skipping topics nobody subscribes to).
        """
        if t_ns < self.now_ns:
            raise ValueError(f"time went backwards: {t_ns} < {self.now_ns}")
        # outputs published before the first tick (in main(), by the constructors) are kept
        # for it: the first tick's output starts with them (step 2 of the module docstring)
        pending: list[Output] = []
        if not self._started:
            # the sim clock starts with the first tick: timers created before it (in main())
            # count their first period from then, as rclpy's do once /clock arrives
            self._started = True
            for tm in self._timers:
                tm.next_due_ns = t_ns + tm.timer_period_ns
            pending = self._outputs
            # to the subscriptions that exist now, whenever they were created (what /tf_static's
            # latching does in ROS, and what a node created after the publisher expects)
            self._queue = deque(pending)
        self.now_ns = t_ns
        self._outputs = pending
        self._local = 0
        self._drain()  # the constructors' local deliveries, before any timer or input
        self._fire_timers(t_ns)
        for topic, msg in inputs:
            self._deliver(topic, msg)
        out, self._outputs = self._outputs, []
        return out

    def _fire_timers(self, t_ns: int) -> None:
        due = [(tm.next_due_ns, i, tm) for i, tm in enumerate(self._timers)]
        for when, _, tm in sorted((d for d in due if d[0] <= t_ns), key=lambda d: d[:2]):
            if tm.cancelled:
                continue
            period = tm.timer_period_ns
            missed = (t_ns - when) // period
            tm.next_due_ns = when + (missed + 1) * period
            tm.callback()
            self._drain()

    def _deliver(self, topic: str, msg: msgs.Message) -> None:
        for sub in tuple(self._subs.get(topic, ())):
            if not isinstance(msg, sub.msg_type):
                raise TypeError(
                    f"subscription of node {sub.node.get_name()!r} on {topic} expects "
                    f"{sub.msg_type.__name__}, but {topic} carries {type(msg).__name__}"
                )
            sub.callback(msg)
            self._drain()

    def _drain(self) -> None:
        while self._queue:
            self._local += 1
            if self._local > MAX_LOCAL_DELIVERIES:
                raise RuntimeError(
                    f"more than {MAX_LOCAL_DELIVERIES} messages delivered within the mission in "
                    "one tick: a callback keeps publishing to a topic it subscribes to"
                )
            topic, msg = self._queue.popleft()
            for sub in tuple(self._subs.get(topic, ())):
                if isinstance(msg, sub.msg_type):
                    sub.callback(msg)
                    # deliveries this callback caused go after the ones already queued (FIFO)


def shutdown(reason: str = "") -> None:
    """rclpy.shutdown(): the mission is done; the run ends after the current tick."""
    current_executor().request_shutdown(reason)
