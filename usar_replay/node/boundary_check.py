"""The recorder's check of everything a mission process sends back: the trust boundary's gate.

Why a gate of its own: the mission process runs untrusted code and may be modified (its copy of
usar's node API is the student's to change), so whatever it sends is checked again here, on the
recorder's side, before a byte of it reaches the log, the simulator or the grade. Every problem
ends the run as ``refused`` with the reason, in a closed, gradeable log; nothing the mission
sends can crash the recorder (today's ``struct.error`` on a garbage frame, the writer's
``ValueError`` on a topic with two types).

What is refused (the limits are documented in docs/node-api.md, "Limits"):

* more than :data:`MAX_TICK_MESSAGES` messages in one tick (a flood of ``/rosout`` lines);
* more than :data:`MAX_MESSAGE_TRANSFORMS` transforms in one ``TFMessage`` or
  ``FiducialTransformArray``, or :data:`MAX_TICK_TRANSFORMS` in one tick's messages together
  (each is work for the grader's tf buffer: a grade bomb);
* a message over :data:`MAX_MESSAGE_BYTES` (8 MiB) of CDR, or a tick over
  :data:`MAX_FRAME_BYTES` in all (the parent reads no further than that);
* a type usar does not know, bytes that do not decode as the type they claim, a topic name over
  :data:`MAX_TOPIC_CHARS` characters, more than :data:`MAX_TOPICS` topics in a run;
* a topic re-used with a second type, or a course topic with the wrong type (``cmd_vel`` is a
  ``Twist``, ``/tf`` a ``TFMessage``, ...: :data:`FIXED_TYPES`);
* NaN or infinity in any float (:mod:`usar_replay.core.finite`);
* what the :class:`~usar_replay.node.executor.PublishPolicy` forbids (ground truth, the
  simulator's topics and tf links, the course's trusted detections).

The mission process applies the same limits at the call, so an honest mission gets the error
where it published (a ``ValueError`` with its own traceback) and the same ``refused`` verdict.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

from usar_replay.core import cdr, contract, msgs
from usar_replay.core.finite import nonfinite_field

__all__ = [
    "FIXED_TYPES",
    "MAX_FRAME_BYTES",
    "MAX_MESSAGE_BYTES",
    "MAX_MESSAGE_TRANSFORMS",
    "MAX_TICK_MESSAGES",
    "MAX_TICK_TRANSFORMS",
    "MAX_TOPICS",
    "MAX_TOPIC_CHARS",
    "BoundaryCheck",
    "OutputRefused",
    "PublishRefused",
    "transforms_problem",
]

MAX_MESSAGE_BYTES = 8 * 1024 * 1024
"""The largest message a mission may publish, in CDR bytes (8 MiB: a camera frame of the course
world is ~0.3 MiB; nothing a mission publishes comes near)."""
MAX_TICK_MESSAGES = 10_000
"""Messages a mission may publish in one tick (the built-in mission publishes about ten)."""
MAX_MESSAGE_TRANSFORMS = 1_000
"""Transforms one ``TFMessage`` or ``FiducialTransformArray`` may carry (the course's largest is
the simulator's ``/tf_static``, a dozen; the built-in mission's marker frames, one or two)."""
MAX_TICK_TRANSFORMS = 10_000
"""Transforms a mission may publish in one tick, all its messages together."""
MAX_FRAME_BYTES = 64 * 1024 * 1024
"""All of one tick's outputs together, as framed on the wire (the parent reads no more)."""
MAX_TOPICS = 1_000
"""Distinct topics a mission may publish on in one run (each is a channel of the log)."""
MAX_TOPIC_CHARS = 256
"""The longest topic name a mission may use."""

FIXED_TYPES: dict[str, str] = {
    contract.TF: msgs.TFMessage.__msgtype__,
    contract.TF_STATIC: msgs.TFMessage.__msgtype__,
    contract.ROSOUT: msgs.Log.__msgtype__,
    contract.FIDUCIALS: msgs.FiducialTransformArray.__msgtype__,
    contract.MARKER_POSES: msgs.FiducialTransformArray.__msgtype__,
    contract.ENABLE_DETECTIONS: msgs.Bool.__msgtype__,
    **{
        contract.cmd_vel(r): msgs.Twist.__msgtype__ for r in (*contract.ROBOTS, contract.ROS2_ROBOT)
    },
}
"""Course topics whose type the recorder, the simulator or the grader rely on."""

_KNOWN_TYPES = frozenset(cls.__msgtype__ for cls in msgs.MESSAGE_TYPES)

Wire = tuple[str, str, bytes]
Checked = tuple[str, str, bytes, msgs.Message]


class PublishPolicy(Protocol):
    """What :class:`usar_replay.node.executor.PublishPolicy` answers (a protocol: the executor
    imports this module's limits)."""

    def message_problem(self, topic: str, msg: msgs.Message) -> str: ...


class OutputRefused(ValueError):
    """What a mission sent may not be accepted; ``str()`` says what and where (one line)."""


class PublishRefused(PermissionError):
    """A mission published (or subscribed to) what the course forbids it: ground truth, the
    simulator's topics and tf links, the course's trusted detections. The run's verdict is
    ``refused``."""


def _transform_count(msg: msgs.Message) -> int:
    if isinstance(msg, msgs.TFMessage | msgs.FiducialTransformArray):
        return len(msg.transforms)
    return 0


def transforms_problem(topic: str, msg: msgs.Message) -> str:
    """Why ``msg`` carries too many transforms to be accepted ('' when it does not)."""
    n = _transform_count(msg)
    if n > MAX_MESSAGE_TRANSFORMS:
        return (
            f"{topic}: a {type(msg).__name__} with {n} transforms; a message carries at most "
            f"{MAX_MESSAGE_TRANSFORMS}"
        )
    return ""


class BoundaryCheck:
    """The parent's per-run state: which type each topic has; :meth:`check` one tick."""

    def __init__(self, policy: PublishPolicy) -> None:
        self.policy = policy
        self.types: dict[str, str] = {}

    def check(self, items: Sequence[Wire]) -> list[Checked]:
        """One tick's outputs, decoded and checked; :class:`OutputRefused` on the first
        problem (nothing of a refused tick is used)."""
        if len(items) > MAX_TICK_MESSAGES:
            raise OutputRefused(
                f"the mission published {len(items)} messages in one tick; at most "
                f"{MAX_TICK_MESSAGES} are accepted"
            )
        checked = [self._one(topic, msgtype, data) for topic, msgtype, data in items]
        total = sum(_transform_count(value) for *_, value in checked)
        if total > MAX_TICK_TRANSFORMS:
            raise OutputRefused(
                f"the mission published {total} transforms in one tick; at most "
                f"{MAX_TICK_TRANSFORMS} are accepted"
            )
        return checked

    def _one(self, topic: str, msgtype: str, data: bytes) -> Checked:
        shown = topic if len(topic) <= MAX_TOPIC_CHARS else topic[:MAX_TOPIC_CHARS] + "..."
        if len(topic) > MAX_TOPIC_CHARS:
            raise OutputRefused(f"topic name {shown!r} is over {MAX_TOPIC_CHARS} characters")
        if len(data) > MAX_MESSAGE_BYTES:
            raise OutputRefused(
                f"the mission published {len(data)} bytes on {topic}; a message is at most "
                f"{MAX_MESSAGE_BYTES} bytes (8 MiB)"
            )
        if msgtype not in _KNOWN_TYPES:
            raise OutputRefused(f"the mission published type {msgtype!r} on {topic}: unknown")
        self._check_type(topic, msgtype)
        try:
            value = cdr.decode(data, msgtype)
        except Exception as err:  # noqa: BLE001 - any decoding failure is the mission's
            raise OutputRefused(
                f"the mission published bytes on {topic} that do not decode as {msgtype} "
                f"({type(err).__name__})"
            ) from None
        problem = self.policy.message_problem(topic, value) or transforms_problem(topic, value)
        if problem:
            raise OutputRefused(problem)
        where = nonfinite_field(value)
        if where:
            raise OutputRefused(
                f"{topic}: {type(value).__name__}.{where}: NaN and infinity are refused"
            )
        return (topic, msgtype, data, value)

    def _check_type(self, topic: str, msgtype: str) -> None:
        known = self.types.get(topic) or FIXED_TYPES.get(topic)
        if known is not None and known != msgtype:
            raise OutputRefused(
                f"{topic} carries {known}; the mission published a {msgtype} on it (one "
                "topic, one type)"
            )
        if topic not in self.types:
            if len(self.types) >= MAX_TOPICS:
                raise OutputRefused(f"the mission published on more than {MAX_TOPICS} topics")
            self.types[topic] = msgtype
