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

__all__ = ["SafeStream", "safe", "safe_line", "safe_stdout"]

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
