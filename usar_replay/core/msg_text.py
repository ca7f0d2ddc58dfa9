"""Messages as YAML-like text, the way ``ros2 topic echo`` prints them, within a width.

Why our own printer: a student reading a log (``usar echo``) expects the block layout of
``rostopic echo`` / ``ros2 topic echo`` (nested fields indented by two, arrays of messages as
``- `` items, ``---`` between messages), but a terminal of 100 columns, and no flood of image
bytes. So numeric arrays are printed in flow style (``[0.0, 0.1, ...]``) wrapped to the width
and elided past :data:`MAX_ITEMS` items, byte fields (an image's ``data``, a map's cells) are
``<6,512 bytes>``, and a long string is a double-quoted YAML string continued with ``\\`` on
the next line (the text reads back unchanged). ``full=True`` prints every item and byte, like
``ros2 topic echo --full-length``.

Field paths (``--fields linear.x,transforms.0.child_frame_id``) are checked against the message
*type* before any message is read, so a typo is one error naming the fields there are, not a
blank output. Pure: message values in, lines out.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from usar_replay.core.msgs import FieldKind, Message, field_kinds

__all__ = [
    "MAX_ITEMS",
    "WIDTH",
    "FieldPath",
    "FieldPathError",
    "field_path",
    "message_lines",
    "path_lines",
    "value_lines",
]

WIDTH = 100
"""The widest line printed (the README's and every command's limit)."""
MAX_ITEMS = 64
"""Array items printed before the rest is elided (a covariance's 36 and a camera's 12 fit)."""

_INDENT = 2
_RESERVED = frozenset({"", "~", "null", "true", "false", "yes", "no", "on", "off", "y", "n"})
_START = frozenset("-?:,[]{}#&*!|>'\"%@`. ")


class FieldPathError(ValueError):
    """A ``--fields`` path that the message type does not have; the text names what it has."""


@dataclass(frozen=True, slots=True)
class FieldPath:
    """A checked dotted path into a message type: its parts (names, and list indexes as
    ints) and the kind of value it leads to (:data:`usar_replay.core.msgs.FieldKind`)."""

    text: str
    parts: tuple[str | int, ...]
    kind: FieldKind
    element: Any
    """The message class for kinds ``msg`` and ``msgs``; None otherwise."""

    def get(self, value: Message) -> Any:
        """The value at this path; None where a list index is past the message's list."""
        out: Any = value
        for part in self.parts:
            if isinstance(part, int):
                if part >= len(out):
                    return None
                out = out[part]
            else:
                out = getattr(out, part)
        return out


_ITEM_KIND: dict[str, FieldKind] = {"msgs": "msg", "floats": "float", "ints": "int", "bytes": "int"}


def field_path(cls: type[Message], text: str) -> FieldPath:
    """Check ``text`` (``pose.position.x``, ``transforms.0.header``) against ``cls``.

    Raises :class:`FieldPathError` saying which part is wrong and what is there instead.
    """
    kind: FieldKind = "msg"
    element: Any = cls
    parts: list[str | int] = []
    for word in text.split("."):
        here = ".".join(str(p) for p in parts) or cls.__msgtype__
        if kind in _ITEM_KIND:  # a list: only an index goes on
            if not word.isdigit():
                raise FieldPathError(
                    f"{here} is a list; follow it with an item's index, e.g. {here}.0"
                )
            parts.append(int(word))
            kind = _ITEM_KIND[kind]
            continue
        if kind != "msg":
            raise FieldPathError(f"{here} is a single value ({kind}); it has no field {word!r}")
        fields = {name: (k, elem) for name, k, elem in field_kinds(element)}
        if word not in fields:
            names = ", ".join(fields)
            raise FieldPathError(
                f"{element.__msgtype__} has no field {word!r}; its fields: {names}"
            )
        parts.append(word)
        kind, element = fields[word]
    return FieldPath(text, tuple(parts), kind, element if kind in ("msg", "msgs") else None)


def message_lines(value: Message, *, width: int = WIDTH, full: bool = False) -> list[str]:
    """Every field of ``value``, one ``name: value`` per line, nested fields indented."""
    return _Printer(width, full).fields(value, 0)


def value_lines(value: Any, *, width: int = WIDTH, full: bool = False) -> list[str]:
    """:func:`message_lines` of a message usar has no type for (rosbags' dataclass value of a
    ROS 1 message kept as its own bytes): each field's kind is read off its value."""
    return _ValuePrinter(width, full).fields(value, 0)


def path_lines(
    path: FieldPath, value: Message, *, width: int = WIDTH, full: bool = False
) -> list[str]:
    """``path.text: value`` for one selected field of ``value`` (nested values below it)."""
    got = path.get(value)
    if got is None:  # an index past this message's list
        return [f"{path.text}: null"[:width]]
    return _Printer(width, full).keyed(path.text, path.kind, got, 0)


class _Printer:
    """The layout rules, bound to one width and one elision choice."""

    def __init__(self, width: int, full: bool) -> None:
        self.width = width
        self.full = full

    def fields(self, value: Message, indent: int) -> list[str]:
        out: list[str] = []
        for name, kind, _ in field_kinds(type(value)):
            out += self.keyed(name, kind, getattr(value, name), indent)
        return out or [" " * indent + "{}"]

    def keyed(self, key: str, kind: FieldKind, value: Any, indent: int) -> list[str]:
        pad = " " * indent
        if kind == "msg":
            return [f"{pad}{key}:", *self.fields(value, indent + _INDENT)]
        if kind == "msgs":
            return self._items(f"{pad}{key}:", value, indent)
        if kind == "bytes" and not self.full:
            return [f"{pad}{key}: <{len(value):,} bytes>"]
        if kind in ("bytes", "floats", "ints"):
            return self._flow(f"{pad}{key}: ", [_scalar(v) for v in value], indent + _INDENT)
        if kind == "str":
            return _string(f"{pad}{key}: ", value, indent + _INDENT, self.width)
        return [f"{pad}{key}: {_scalar(value)}"]

    def _items(self, head: str, items: Sequence[Message], indent: int) -> list[str]:
        if not items:
            return [head + " []"]
        out = [head]
        shown = items if self.full else items[:MAX_ITEMS]
        inner = indent + _INDENT
        for item in shown:
            lines = self.fields(item, inner)
            lines[0] = " " * indent + "- " + lines[0][inner:]
            out += lines
        if len(items) > len(shown):
            out.append(f"{' ' * indent}# ... {len(items) - len(shown):,} more items")
        return out

    def _flow(self, head: str, words: list[str], indent: int) -> list[str]:
        """``head[a, b, c]``, wrapped at the width with continuation lines at ``indent``."""
        if not self.full and len(words) > MAX_ITEMS:
            words = [*words[:MAX_ITEMS], f"... {len(words) - MAX_ITEMS:,} more"]
        if not words:
            return [head + "[]"]
        lines: list[str] = []
        line = head + "["
        for i, word in enumerate(words):
            piece = word + ("]" if i == len(words) - 1 else ",")
            if len(line) + 1 + len(piece) > self.width and not line.endswith("["):
                lines.append(line)
                line = " " * indent + piece
            else:
                line += ("" if line.endswith("[") else " ") + piece
        lines.append(line)
        return lines


class _ValuePrinter(_Printer):
    """The same layout for a value whose class is not a :class:`Message` (rosbags')."""

    def fields(self, value: Any, indent: int) -> list[str]:
        out: list[str] = []
        for f in dataclasses.fields(value):
            if not f.name.startswith("_"):
                item = getattr(value, f.name)
                out += self.keyed(f.name, _kind_of(item), item, indent)
        return out or [" " * indent + "{}"]


def _kind_of(value: Any) -> FieldKind:
    """A rosbags field's kind, from its value (numpy arrays of numbers, lists of messages)."""
    if dataclasses.is_dataclass(value):
        return "msg"
    dtype = getattr(value, "dtype", None)
    if dtype is not None:
        if dtype.kind in "ui" and dtype.itemsize == 1:
            return "bytes"
        return "floats" if dtype.kind == "f" else "ints"
    if isinstance(value, list | tuple):
        if value and dataclasses.is_dataclass(value[0]):
            return "msgs"
        return "floats" if any(isinstance(v, float) for v in value) else "ints"
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, str):
        return "str"
    return "float" if isinstance(value, float) else "int"


def _scalar(value: Any) -> str:
    """A number or bool as YAML writes it (``1.0e-05``, ``.nan``, ``true``)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        if math.isnan(value):
            return ".nan"
        if math.isinf(value):
            return ".inf" if value > 0 else "-.inf"
        text = repr(value)
        mantissa, e, exponent = text.partition("e")
        if e and "." not in mantissa:  # YAML reads 1e-05 as a string, 1.0e-05 as a number
            text = f"{mantissa}.0e{exponent}"
        return text
    return str(value)


def _plain(text: str) -> bool:
    """Whether ``text`` can be written unquoted and still read back as this string."""
    if text.lower() in _RESERVED or text[0] in _START or text[-1] == " ":
        return False
    if ": " in text or " #" in text or text.endswith(":"):
        return False
    if not text.isprintable():
        return False
    try:
        float(text)
    except ValueError:
        return True
    return False


def _escape(ch: str) -> str:
    """One character inside a YAML double-quoted string."""
    if ch == "\\":
        return "\\\\"
    if ch == '"':
        return '\\"'
    if ch == "\n":
        return "\\n"
    if ch == "\t":
        return "\\t"
    if not ch.isprintable():
        code = ord(ch)
        return f"\\x{code:02x}" if code < 0x100 else f"\\u{code:04x}"
    return ch


def _string(head: str, text: str, indent: int, width: int) -> list[str]:
    """``head`` + the string: plain or single-quoted when it fits on the line, otherwise
    double-quoted and continued with a trailing ``\\`` (an escaped line break, which YAML
    drops together with the next line's indent, so the text reads back unchanged)."""
    if text and _plain(text) and len(head) + len(text) <= width:
        return [head + text]
    if text.isprintable() and len(head) + len(text) + 2 <= width:
        return [head + "'" + text.replace("'", "''") + "'"]
    lines: list[str] = []
    prefix = head + '"'
    line: list[str] = []
    used = len(prefix)
    room = width - 1  # each line ends with a backslash or the closing quote
    for ch in text:
        token = _escape(ch)
        if line and used + len(token) > room:
            cut = _word_break(line)
            lines.append(prefix + "".join(line[:cut]) + "\\")
            prefix, line = " " * indent, line[cut:]
            if line and line[0] == " ":
                line[0] = "\\ "
            used = len(prefix) + sum(map(len, line))
        if lines and not line and token == " ":
            token = "\\ "  # a continuation line's leading space would be read as indent
        line.append(token)
        used += len(token)
    lines.append(prefix + "".join(line) + '"')
    return lines


def _word_break(line: list[str]) -> int:
    """How many tokens a continued line keeps: up to its last space among the last 20, so
    words stay whole, or all of them when there is none."""
    for i in range(len(line) - 1, max(len(line) - 21, 0), -1):
        if line[i] == " ":
            return i + 1
    return len(line)
