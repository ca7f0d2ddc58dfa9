"""An rclpy-shaped ``Node`` for mission code: subscriptions, publishers, timers, clock, logger,
parameters.

Why rclpy's shape: the people who write missions for this course wrote ROS nodes; the calls they
know (``create_subscription(Twist, "/cmd_vel", cb)``, ``get_clock().now()``,
``get_logger().info(...)``, ``get_parameter("x").value``) work here with the same names and
meanings. What differs is only what makes a run replayable:

* there is no ``rclpy.spin``: usar runs your nodes (see :mod:`usar_replay.node.executor` for the
  order in which callbacks run); you create them in your mission's ``main()``;
* the clock is the simulator's (``/clock`` semantics, ``use_sim_time`` always true); nothing here
  reads the wall clock;
* messages are immutable values from :mod:`usar_replay.core.msgs`, built with keyword arguments
  (``Twist(linear=Vector3(x=0.2))``), since a message you published must not change afterwards;
* QoS arguments are accepted for compatibility and ignored: delivery is reliable and in order.

A node belongs to the executor that is current when it is created (rclpy's default context):
the mission process makes one current before it calls your ``main()``.
"""

from __future__ import annotations

import contextvars
import math
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any, Protocol, TypeVar

from usar_replay.core import msgs

__all__ = [
    "Clock",
    "Duration",
    "Logger",
    "Node",
    "Parameter",
    "ParameterNotDeclared",
    "Publisher",
    "Subscription",
    "Time",
    "Timer",
    "current_executor",
    "reset_current_executor",
    "set_current_executor",
]

M = TypeVar("M", bound=msgs.Message)


class Executor(Protocol):
    """What a node needs from the executor it belongs to
    (:class:`usar_replay.node.executor.Executor` implements it; a protocol keeps this module
    free of the executor's import)."""

    now_ns: int
    parameters: dict[str, Any]

    def add_node(self, node: Node) -> None: ...
    def remove_node(self, node: Node) -> None: ...
    def add_subscription(self, sub: Subscription) -> None: ...
    def add_timer(self, timer: Timer) -> None: ...
    def subscription_count(self, topic: str) -> int: ...
    def provided_by_world(self, topic: str) -> bool: ...
    def check_publish_topic(self, topic: str) -> None: ...
    def publish(self, topic: str, msg: msgs.Message) -> None: ...
    def log(self, name: str, level: int, text: str) -> None: ...
    def request_shutdown(self, reason: str = "") -> None: ...


_CURRENT: contextvars.ContextVar[Executor | None] = contextvars.ContextVar(
    "usar_executor", default=None
)


def current_executor() -> Executor:
    """The executor nodes join when created (set by the mission process or by a test)."""
    ex = _CURRENT.get()
    if ex is None:
        raise RuntimeError(
            "no usar executor is running: create your nodes inside the mission's main(), which "
            "`usar record --mission` and `usar replay --mission` call (or inside "
            "`with Executor(...).activate():` in a test)"
        )
    return ex


def set_current_executor(ex: Executor | None) -> contextvars.Token[Executor | None]:
    """Make ``ex`` the executor new nodes join (the executor's ``activate()`` calls it)."""
    return _CURRENT.set(ex)


def reset_current_executor(token: contextvars.Token[Executor | None]) -> None:
    """Undo the :func:`set_current_executor` that gave ``token``."""
    _CURRENT.reset(token)


# --- time ------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True, order=True)
class Duration:
    """rclpy.duration.Duration: a span of sim time in integer nanoseconds."""

    nanoseconds: int = 0

    @classmethod
    def from_seconds(cls, seconds: float) -> Duration:
        return cls(round(seconds * 1e9))

    def to_msg(self) -> msgs.Duration:
        sec, nsec = divmod(self.nanoseconds, 1_000_000_000)
        return msgs.Duration(sec=sec, nanosec=nsec)


@dataclass(frozen=True, slots=True, order=True)
class Time:
    """rclpy.time.Time on the sim clock: integer nanoseconds, ``Time()`` is zero ("latest"
    for tf2 lookups, as in tf2_ros)."""

    nanoseconds: int = 0

    @classmethod
    def from_msg(cls, stamp: msgs.Time) -> Time:
        return cls(stamp.ns)

    def to_msg(self) -> msgs.Time:
        return msgs.Time.from_ns(self.nanoseconds)

    def seconds_nanoseconds(self) -> tuple[int, int]:
        return divmod(self.nanoseconds, 1_000_000_000)

    @property
    def seconds(self) -> float:
        """Convenience (not in rclpy): the time as float seconds."""
        return self.nanoseconds / 1e9

    def __add__(self, other: Duration) -> Time:
        return Time(self.nanoseconds + other.nanoseconds)

    def __sub__(self, other: Time) -> Duration:
        return Duration(self.nanoseconds - other.nanoseconds)


class Clock:
    """The sim clock of a node (``use_sim_time``): ``now()`` is the time of the message (or
    timer) being handled."""

    def __init__(self, executor: Executor) -> None:
        self._executor = executor

    def now(self) -> Time:
        return Time(self._executor.now_ns)


# --- parameters ------------------------------------------------------------------------------


class ParameterNotDeclared(KeyError):
    """rclpy's ``ParameterNotDeclaredException``: the name is neither declared nor given."""


@dataclass(frozen=True, slots=True)
class Parameter:
    """rclpy.parameter.Parameter: a name and a value (bool, int, float, str or a list of them)."""

    name: str
    value: Any = None

    def get_parameter_value(self) -> Parameter:
        """rclpy returns a ParameterValue; the common ``.value`` works on this object too."""
        return self

    @property
    def double_array_value(self) -> list[float]:
        return [float(v) for v in self.value]

    @property
    def double_value(self) -> float:
        return float(self.value)

    @property
    def integer_value(self) -> int:
        return int(self.value)

    @property
    def string_value(self) -> str:
        return str(self.value)

    @property
    def bool_value(self) -> bool:
        return bool(self.value)


# --- logging ---------------------------------------------------------------------------------


class Logger:
    """rclpy's node logger: each line goes to ``/rosout`` as ``rcl_interfaces/Log``, stamped with
    sim time (and so into the log and the viewer)."""

    def __init__(self, node: Node) -> None:
        self._node = node

    @property
    def name(self) -> str:
        return self._node.get_name()

    def _log(self, level: int, text: str) -> None:
        self._node._executor.log(self._node.get_name(), level, str(text))

    def debug(self, text: str) -> None:
        self._log(msgs.Log.DEBUG, text)

    def info(self, text: str) -> None:
        self._log(msgs.Log.INFO, text)

    def warning(self, text: str) -> None:
        self._log(msgs.Log.WARN, text)

    warn = warning

    def error(self, text: str) -> None:
        self._log(msgs.Log.ERROR, text)

    def fatal(self, text: str) -> None:
        self._log(msgs.Log.FATAL, text)


# --- endpoints -------------------------------------------------------------------------------


class Publisher:
    """rclpy.publisher.Publisher: ``publish(msg)`` sends ``msg`` at the current sim time."""

    def __init__(self, node: Node, msg_type: type[msgs.Message], topic: str) -> None:
        self.node = node
        self.msg_type = msg_type
        self.topic_name = topic

    def publish(self, msg: msgs.Message) -> None:
        if not isinstance(msg, self.msg_type):
            raise TypeError(
                f"publisher on {self.topic_name} takes {self.msg_type.__name__}, "
                f"got {type(msg).__name__}"
            )
        self.node._executor.publish(self.topic_name, msg)

    def get_subscription_count(self) -> int:
        return self.node._executor.subscription_count(self.topic_name)


class Subscription:
    """rclpy.subscription.Subscription: ``callback(msg)`` for each message on ``topic``."""

    def __init__(
        self,
        node: Node,
        msg_type: type[msgs.Message],
        topic: str,
        callback: Callable[[Any], None],
    ) -> None:
        self.node = node
        self.msg_type = msg_type
        self.topic_name = topic
        self.callback = callback


class Timer:
    """rclpy.timer.Timer on the sim clock: fires every ``period`` of sim time.

    The first call is one period after creation; a timer keeps its phase (the next due time is
    the previous one plus the period), and fires at most once per simulator tick.
    """

    def __init__(self, node: Node, period_ns: int, callback: Callable[[], None]) -> None:
        self.node = node
        self.timer_period_ns = period_ns
        self.callback = callback
        self.next_due_ns = node._executor.now_ns + period_ns
        self.cancelled = False

    def cancel(self) -> None:
        self.cancelled = True

    def reset(self) -> None:
        self.cancelled = False
        self.next_due_ns = self.node._executor.now_ns + self.timer_period_ns

    def is_canceled(self) -> bool:
        return self.cancelled


# --- the node --------------------------------------------------------------------------------


class Node:
    """rclpy.node.Node: create it (or a subclass) in your mission's ``main()``."""

    def __init__(
        self,
        node_name: str,
        *,
        namespace: str = "",
        parameter_overrides: Mapping[str, Any] | None = None,
    ) -> None:
        self._executor = current_executor()
        self._name = node_name
        self._namespace = namespace
        self._declared: dict[str, Parameter] = {}
        self._overrides = dict(parameter_overrides or {})
        self._clock = Clock(self._executor)
        self._logger = Logger(self)
        self.subscriptions: list[Subscription] = []
        self.publishers: list[Publisher] = []
        self.timers: list[Timer] = []
        self._executor.add_node(self)

    # -- identity ------------------------------------------------------------------------------

    def get_name(self) -> str:
        return self._name

    def get_namespace(self) -> str:
        return self._namespace or "/"

    def get_logger(self) -> Logger:
        return self._logger

    def get_clock(self) -> Clock:
        return self._clock

    # -- endpoints -----------------------------------------------------------------------------

    def create_publisher(self, msg_type: type[M], topic: str, qos_profile: Any = 10) -> Publisher:
        """A publisher; the executor refuses topics a mission may not publish (ground truth,
        the simulator's odometry and camera) with :class:`PermissionError`."""
        self._executor.check_publish_topic(topic)
        pub = Publisher(self, msg_type, topic)
        self.publishers.append(pub)
        return pub

    def create_subscription(
        self,
        msg_type: type[M],
        topic: str,
        callback: Callable[[M], None],
        qos_profile: Any = 10,
    ) -> Subscription:
        """``callback(msg)`` for each message on ``topic`` (ground truth is never delivered)."""
        sub = Subscription(self, msg_type, topic, callback)
        self.subscriptions.append(sub)
        self._executor.add_subscription(sub)
        return sub

    def create_timer(self, timer_period_sec: float, callback: Callable[[], None]) -> Timer:
        """A timer on the sim clock (see :class:`Timer` for when it fires)."""
        if not (math.isfinite(timer_period_sec) and timer_period_sec > 0):
            raise ValueError(
                f"timer period must be a positive number of seconds, not {timer_period_sec!r}"
            )
        timer = Timer(self, max(round(timer_period_sec * 1e9), 1), callback)
        self.timers.append(timer)
        self._executor.add_timer(timer)
        return timer

    def destroy_timer(self, timer: Timer) -> None:
        timer.cancel()

    def destroy_node(self) -> None:
        """Stop this node's callbacks (rclpy's destroy_node)."""
        self._executor.remove_node(self)

    # -- parameters ----------------------------------------------------------------------------

    def declare_parameter(self, name: str, value: Any = None) -> Parameter:
        """Declare ``name`` with a default; the run's value (launch parameters) wins."""
        given = self._overrides.get(name, self._executor.parameters.get(name, value))
        p = Parameter(name, given)
        self._declared[name] = p
        return p

    def declare_parameters(
        self, namespace: str, parameters: list[tuple[str, Any]]
    ) -> list[Parameter]:
        prefix = f"{namespace}." if namespace else ""
        return [self.declare_parameter(prefix + n, v) for n, v in parameters]

    def has_parameter(self, name: str) -> bool:
        return name in self._declared or name in self._executor.parameters

    def get_parameter(self, name: str) -> Parameter:
        """The parameter's value: declared ones, or any the run provides (as if
        ``automatically_declare_parameters_from_overrides`` were set, which the course's
        launch files rely on). ROS 1 style ``a/b`` names are read as ROS 2's ``a.b``."""
        name = name.replace("/", ".").lstrip(".")
        if name in self._declared:
            return self._declared[name]
        if name in self._overrides:
            return Parameter(name, self._overrides[name])
        if name in self._executor.parameters:
            return Parameter(name, self._executor.parameters[name])
        known = ", ".join(sorted(self._executor.parameters)[:8])
        raise ParameterNotDeclared(
            f"parameter {name!r} is not declared nor given (given: {known}, ...)"
        )

    def get_parameters_by_prefix(self, prefix: str) -> dict[str, Parameter]:
        """Parameters under ``prefix.`` keyed by the rest of their name, sorted by name."""
        dot = prefix + "." if prefix else ""
        names = sorted({*self._executor.parameters, *self._declared, *self._overrides})
        return {n[len(dot) :]: self.get_parameter(n) for n in names if n.startswith(dot)}

    def iter_parameters(self) -> Iterator[Parameter]:
        for n in sorted(self._executor.parameters):
            yield self.get_parameter(n)
