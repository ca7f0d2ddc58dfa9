"""Text from mission code made safe to print: control characters shown, never obeyed.

Why: a mission's crash traceback, its log lines and its strings are written by the team, and
usar prints them on the grader's terminal. Raw, an escape sequence in them can clear the screen,
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

import unicodedata

__all__ = ["safe", "safe_line"]

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
