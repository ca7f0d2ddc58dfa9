"""Text from mission code or a log made safe to print: control characters shown, never obeyed.

Why: a mission's crash traceback, its log lines and its strings are written by the team, a log's
every string (topic and type names, metadata, node names) by whoever wrote the file, and usar
prints them on the grader's terminal. Raw, an escape sequence in them can clear the screen,
move the cursor and draw a fake "4/4 ... done", rename the terminal's window or (on some
terminals) write to its clipboard. Every place where mission text reaches a terminal passes it
through :func:`safe`, which writes each control character as a visible escape (``\\x1b``,
``\\r``, ``\\u202e``): the text stays readable and the terminal does nothing.

What stays: printable characters (any script), and, when the text is several lines (a
traceback), newline and tab. Escaped: the C0 and C1 control characters (ESC, BEL, carriage
return, backspace, ...), DEL, and Unicode's format characters (category ``Cf``: the
right-to-left overrides that reorder what a reader sees, zero-width joiners) and separators
that break a line outside ``\\n`` (U+2028, U+2029).
"""

from __future__ import annotations

import contextlib
import io
import sys
import unicodedata
from collections.abc import Iterable, Iterator
from typing import TextIO

__all__ = ["MAX_LINE", "SafeStream", "safe", "safe_line", "safe_stdout", "team_lines"]

MAX_LINE = 400
"""Characters kept of one line of a team's text (a build's error, a node's output) for a
person; the rest is cut, and the cut is said."""

_KEPT_IN_LINES = frozenset("\n\t")


def _shown(ch: str) -> str:
    code = ord(ch)
    if code < 0x100:
        return f"\\x{code:02x}"
    return f"\\u{code:04x}" if code < 0x10000 else f"\\U{code:08x}"


def _harmless(ch: str) -> bool:
    return unicodedata.category(ch) not in ("Cc", "Cf", "Zl", "Zp", "Cs", "Co", "Cn")


def safe(text: str, *, lines: bool = True) -> str:
    """``text`` with every control character written as an escape (see the module's docstring).

    ``lines``: keep newline and tab (a multi-line traceback stays readable); False for text
    shown on one line (a status line, a table cell), where a newline is escaped too."""
    if text.isprintable():
        return text  # the common case: nothing to escape (isprintable rejects \n and \t too)
    kept = _KEPT_IN_LINES if lines else frozenset()
    return "".join(ch if ch in kept or _harmless(ch) else _shown(ch) for ch in text)


def safe_line(text: str) -> str:
    """``text`` for one line of output: :func:`safe` with newline and tab escaped too."""
    return safe(text, lines=False)


def team_lines(text: str, max_len: int = MAX_LINE) -> list[str]:
    """A team's text (build output, a node's output) as lines for a person: split at newlines
    only (``str.splitlines`` also splits at a carriage return, a form feed, U+2028: a build's
    ``message(FATAL_ERROR "...\\r usar: exit 0: 60/60 PASS")`` would start a line of its own),
    each line with every control character escaped (:func:`safe_line`; tabs expanded) and cut
    past ``max_len`` characters, so that nothing a team prints can start a line or look like
    one of usar's."""
    out: list[str] = []
    for line in text.split("\n"):
        shown = safe_line(line.expandtabs(4))
        if len(shown) > max_len:
            shown = f"{shown[:max_len]}... [{len(shown) - max_len} more characters]"
        out.append(shown)
    return out


class SafeStream(io.TextIOBase):
    """A text stream that writes everything through :func:`safe` (newline and tab kept) to
    another: what the CLI puts in place of ``sys.stdout``.

    Why, beside escaping where each string is formatted: a log is hostile input, and its strings
    (topic and type names, metadata, a node's name, a message's text) reach stdout along many
    paths (``info``, ``echo``, ``log``, ``grade``'s table, ``replay``'s report); one path missed
    would let an escape sequence through. usar never means a control character on stdout (its
    progress bars are rich's, on stderr), so escaping all of them there costs nothing and
    closes every path at once. Everything else (``fileno``, ``isatty``, ``flush``) is the
    wrapped stream's."""

    def __init__(self, stream: TextIO) -> None:
        super().__init__()
        self.stream = stream

    def write(self, text: str) -> int:
        self.stream.write(safe(text))
        return len(text)

    def writelines(self, lines: Iterable[str]) -> None:  # type: ignore[override]
        for line in lines:
            self.write(line)

    def flush(self) -> None:
        self.stream.flush()

    def fileno(self) -> int:
        return self.stream.fileno()

    def isatty(self) -> bool:
        return self.stream.isatty()

    def writable(self) -> bool:
        return True

    @property
    def encoding(self) -> str:  # type: ignore[override]
        return self.stream.encoding

    @property
    def errors(self) -> str | None:  # type: ignore[override]
        return self.stream.errors


@contextlib.contextmanager
def safe_stdout() -> Iterator[None]:
    """``sys.stdout`` as a :class:`SafeStream` for the block (restored after, flushed)."""
    real = sys.stdout
    guarded = SafeStream(real)
    sys.stdout = guarded
    try:
        yield
    finally:
        if sys.stdout is guarded:
            sys.stdout = real
        with contextlib.suppress(OSError, ValueError):
            real.flush()
