"""The recorder's check of what the bridge sends back, with a ROS 1 package's own topics.

Why its own check: :class:`usar_replay.node.boundary_check.BoundaryCheck` accepts only usar's
ROS 2 types and holds ``/explorer/marker_poses`` to the built-in mission's
``FiducialTransformArray``. A ROS 1 package publishes what it likes on its own topics (its
stored markers as a ``geometry_msgs/PoseArray``, a type of its own package), and the bridge
records all of it (:mod:`usar_replay.ros1.topic_recorder`). Every other limit stays: sizes, topic
names and counts, one type per topic (and one definition per ROS 1 topic), the simulator's and
ground truth's topics refused, non-finite numbers refused in usar's types. A message kept as
its ROS 1 bytes must decode with the definition it came with (rosbags), else ``refused``; the
definitions themselves are capped in shape and, together, per run
(:mod:`usar_replay.core.ros1defs`: a definition past a cap is ``refused`` before it is parsed).
"""

from __future__ import annotations

from usar_replay.core import contract, ros1msg
from usar_replay.core.ros1defs import DefinitionRefused, Definitions
from usar_replay.node.boundary_check import (
    FIXED_TYPES,
    MAX_MESSAGE_BYTES,
    MAX_TOPIC_CHARS,
    MAX_TOPICS,
    BoundaryCheck,
    Checked,
    OutputRefused,
)

__all__ = ["ROS1_FIXED_TYPES", "Ros1BoundaryCheck"]

ROS1_FIXED_TYPES = {t: m for t, m in FIXED_TYPES.items() if t != contract.MARKER_POSES}
"""The course topics whose type is fixed for a ROS 1 package (its stored markers are not)."""


class Ros1BoundaryCheck(BoundaryCheck):
    """:class:`BoundaryCheck` for the bridge's outputs (see the module doc)."""

    def __init__(self, *args: object, **kwargs: object) -> None:
        super().__init__(*args, **kwargs)  # type: ignore[arg-type]
        self.definitions: dict[str, str] = {}
        self.parsed = Definitions()
        """The run's parsed definitions: each parsed once, all within the run's budgets."""

    def _one(self, topic: str, msgtype: str, data: bytes) -> Checked:
        if not msgtype.startswith(ros1msg.WIRE_PREFIX):
            return super()._one(topic, msgtype, data)
        if len(topic) > MAX_TOPIC_CHARS:
            raise OutputRefused(f"topic name {topic[:MAX_TOPIC_CHARS]!r}... is too long")
        if len(data) > MAX_MESSAGE_BYTES:
            raise OutputRefused(
                f"the package published {len(data)} bytes on {topic}; a message is at most "
                f"{MAX_MESSAGE_BYTES} bytes (8 MiB)"
            )
        try:
            value = ros1msg.unpack(msgtype, data)
        except (ValueError, UnicodeDecodeError) as err:
            raise OutputRefused(f"a malformed ROS 1 message on {topic} ({err})") from None
        self._check_type(topic, msgtype)
        known = self.definitions.setdefault(topic, value.definition)
        if known != value.definition:
            raise OutputRefused(
                f"{topic}: a second definition of {value.msgtype} (one topic, one type)"
            )
        try:
            self.parsed.decode(value.msgtype, known, value.data)
        except DefinitionRefused as err:
            raise OutputRefused(f"{topic}: {err}") from None
        except Exception as err:  # noqa: BLE001 - any decoding failure is the package's
            raise OutputRefused(
                f"the package published bytes on {topic} that do not decode as {value.msgtype} "
                f"({type(err).__name__})"
            ) from None
        problem = self.policy.message_problem(topic, value)
        if problem:
            raise OutputRefused(problem)
        return (topic, msgtype, data, value)

    def _check_type(self, topic: str, msgtype: str) -> None:
        known = self.types.get(topic) or ROS1_FIXED_TYPES.get(topic)
        if known is not None and known != msgtype:
            raise OutputRefused(
                f"{topic} carries {known}; the package published a {msgtype} on it (one "
                "topic, one type)"
            )
        if topic not in self.types:
            if len(self.types) >= MAX_TOPICS:
                raise OutputRefused(f"the package published on more than {MAX_TOPICS} topics")
            self.types[topic] = msgtype
