"""`usar echo`: one topic's messages from a log, as ``ros2 topic echo`` prints them.

A workflow over :func:`usar_replay.log.run.open_run` and the pure printer
:mod:`usar_replay.core.msg_text`: the topic is found (or refused with the log's topics, the
closest first), the ``--fields`` paths are checked against the topic's *type* before a message
is read, then each message in the time window is one block::

    # 12.350 s
    linear:
      x: 0.2
      ...
    ---

The comment is the message's log time = its sim time in seconds, the clock ``usar grade``
prints in its 'at' column and ``usar view`` shows on its timeline (the sim clock starts at
1 s), so a grade line's time can be looked up here. A damaged log is echoed as far as it goes:
the caller asks :meth:`Run.problem` afterwards.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass

from usar_replay.core import msg_text, msgs, ros1msg
from usar_replay.core.errors import IncompleteLog, LogError, UsageError
from usar_replay.core.ros1defs import DefinitionRefused, Definitions
from usar_replay.core.safe_text import safe_line
from usar_replay.log.run import Run

__all__ = ["EchoRequest", "blocks", "find_topic"]


@dataclass(frozen=True, slots=True)
class EchoRequest:
    """What to print: a topic, a time window in log-time ns (``until`` included) and fields."""

    topic: str
    since_ns: int | None = None
    until_ns: int | None = None
    fields: tuple[str, ...] = ()
    """Dotted field paths (``linear.x``); empty: every field."""
    full: bool = False
    """Every array item and byte (``--full-length``), not the elided form."""
    width: int = msg_text.WIDTH


def find_topic(run: Run, topic: str) -> str:
    """The log's name for ``topic`` (``explorer/cmd_vel`` finds ``/explorer/cmd_vel``).

    An unknown topic is a :class:`UsageError` naming the closest of the log's topics; in
    a damaged log it is :class:`IncompleteLog` (the topic may lie past the damage).
    """
    topics = list(run.topics)
    for name in (topic, "/" + topic.lstrip("/")):
        if name in run.topics:
            return name
    # the closest match only: the whole list (20-odd topics) would not fit a 100-column line
    import difflib

    close = difflib.get_close_matches(topic, topics, n=1, cutoff=0.5)
    hint = f"did you mean {close[0]}? " if close else ""
    hint += f"(`usar info` lists all {len(topics)})"
    if run.damage is not None:
        raise IncompleteLog(
            f"{run.path}: no topic {topic} in the readable part of the log "
            f"({run.damage.describe()}); {hint}"
        )
    raise UsageError(f"{run.path}: no topic {topic}; {hint}")


def _paths(run: Run, topic: str, fields: Sequence[str]) -> list[msg_text.FieldPath]:
    """The ``--fields`` paths checked against the topic's type (:class:`UsageError` names
    the fields there are)."""
    if not fields:
        return []
    msgtype = run.topics[topic].msgtype
    if run.reader.ros1_definition(topic) is not None:
        raise UsageError(f"--fields: {topic} is a ROS 1 {msgtype}; echo it without --fields")
    try:
        cls = msgs.message_class(msgtype)
    except KeyError:
        raise UsageError(
            f"--fields: {topic} has type {msgtype}, which usar-replay cannot decode"
        ) from None
    out = []
    for text in fields:
        try:
            out.append(msg_text.field_path(cls, text))
        except msg_text.FieldPathError as err:
            raise UsageError(f"--fields {text}: {err}") from None
    return out


def blocks(run: Run, request: EchoRequest) -> Iterator[list[str]]:
    """One block of lines per message on the topic in the window, in log-time order (the
    last line of each is ``---``). Checks the topic and the fields before reading."""
    topic = find_topic(run, request.topic)
    paths = _paths(run, topic, request.fields)
    end = None if request.until_ns is None else request.until_ns + 1
    width, full = request.width, request.full
    ros1 = run.reader.ros1_definition(topic)
    parsed = Definitions()
    if ros1 is not None:  # its shape checked before a message is read (a log is hostile input)
        try:
            parsed.store(*ros1)
        except DefinitionRefused as err:
            raise LogError(f"{run.path}: {safe_line(topic)}: {safe_line(str(err))}") from None
        except Exception:  # noqa: BLE001 - does not parse: each message says so below
            pass
    for m in run.messages([topic], request.since_ns, end):
        lines = [f"# {m.log_time_ns / 1e9:.3f} s"]
        if m.msg is None and ros1 is not None:
            lines += _ros1_lines(topic, m.log_time_ns, ros1, m.data, parsed, width, full)
        elif m.msg is None:
            lines.append(f"# {m.msgtype}: a type usar-replay cannot decode ({len(m.data):,} bytes)")
        elif paths:
            for path in paths:
                lines += msg_text.path_lines(path, m.msg, width=width, full=full)
        else:
            lines += msg_text.message_lines(m.msg, width=width, full=full)
        lines.append("---")
        yield lines


def _ros1_lines(
    topic: str,
    t_ns: int,
    ros1: tuple[str, str],
    data: bytes,
    parsed: Definitions,
    width: int,
    full: bool,
) -> list[str]:
    """A message a ROS 1 package published in a type of its own, read with its recorded
    definition (:mod:`usar_replay.core.ros1msg`), parsed once for the whole echo."""
    try:
        value = ros1msg.decode(*ros1, data, parsed)
    except Exception as err:  # noqa: BLE001 - any decoding failure is the log's
        raise LogError(
            f"message on {safe_line(topic)} at {t_ns / 1e9:.3f} s cannot be decoded as "
            f"{safe_line(ros1[0])}: {safe_line(str(err))}"
        ) from None
    return msg_text.value_lines(value, width=width, full=full)
