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

One helper per medium, used by every writer of that medium (design.md: "team text is data until
an output writes it"), each built on :func:`safe`:

* terminal and text files (``summary.txt``, tables): :func:`safe` / :func:`safe_line`, and
  :class:`SafeStream` on the CLI's stdout;
* CSV: :func:`csv_row` (:func:`csv_cell` per cell): controls escaped, and a cell that begins
  with ``=``, ``+``, ``-``, ``@``, a tab or a carriage return gets a leading ``'`` (OWASP's rule
  against CSV injection: a team folder named ``=HYPERLINK("https://evil.invalid", "open")``
  is a clickable link in LibreOffice and Excel otherwise); a plain number stays a number;
* HTML: :func:`html_text`: controls escaped, then ``html.escape`` (quotes included);
* JSON: :func:`json_data` on the document before ``json.dumps``: every string (keys too) with
  its controls escaped, so that what a reader of the JSON shows (Gradescope's output box, a
  spreadsheet's import) holds no raw ESC, C1 control, bidi override or line separator
  (``json.dumps`` escapes C0 only, and only in its bytes: decoded, they are raw again).
"""

from __future__ import annotations

import codecs
import contextlib
import html
import io
import os
import re
import sys
import unicodedata
from collections.abc import Iterable, Iterator
from typing import Any, TextIO

__all__ = [
    "MAX_LINE",
    "SafeStream",
    "csv_cell",
    "csv_row",
    "html_text",
    "json_data",
    "safe",
    "safe_copy",
    "safe_line",
    "safe_stdout",
    "team_lines",
]

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


_FORMULA_START = ("=", "+", "-", "@", "\t", "\r")
"""What a spreadsheet reads as the start of a formula (OWASP, "CSV Injection")."""
_NUMBER = re.compile(r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?")


def csv_cell(value: object) -> object:
    """One CSV cell: a string with its controls escaped (:func:`safe_line`) and, when it begins
    with a formula character (``= + - @``, tab, CR) and is not a plain number, a ``'`` in front
    so that a spreadsheet shows it as text; numbers and None as they are."""
    if not isinstance(value, str):
        return value
    text = safe_line(value)
    if text.startswith(_FORMULA_START) and not _NUMBER.fullmatch(text):
        return "'" + text
    return text


def csv_row(values: Iterable[object]) -> list[object]:
    """A row for ``csv.writer``: every cell through :func:`csv_cell`."""
    return [csv_cell(v) for v in values]


def html_text(text: str, *, lines: bool = True) -> str:
    """``text`` for HTML: controls escaped (:func:`safe`; newline and tab kept with ``lines``,
    for a ``<pre>``), then ``&``, ``<``, ``>`` and both quotes as entities (an attribute's value
    too)."""
    return html.escape(safe(str(text), lines=lines), quote=True)


def json_data(value: Any) -> Any:
    """``value`` (a JSON-ready document) with every string in it, keys included, through
    :func:`safe` (newline and tab kept: ``json.dumps`` writes them as ``\\n``, ``\\t``)."""
    if isinstance(value, str):
        return safe(value)
    if isinstance(value, dict):
        return {json_data(k): json_data(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_data(v) for v in value]
    return value


def safe_copy(source: str | os.PathLike[str], target: str | os.PathLike[str]) -> None:
    """A text file a team's processes wrote (a run's ``output.txt``: what its mission printed)
    copied to ``target`` for people, every control escaped (:func:`safe`, newline and tab
    kept), read a megabyte at a time (the file is as long as the run's output was): ``cat`` of
    it in a terminal draws nothing the team chose. Bytes that are not UTF-8 are shown as
    U+FFFD."""
    decoder = codecs.getincrementaldecoder("utf-8")(errors="replace")
    with open(source, "rb") as src, open(target, "w", encoding="utf-8", newline="") as dst:
        while block := src.read(1 << 20):
            dst.write(safe(decoder.decode(block)))
        dst.write(safe(decoder.decode(b"", final=True)))


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
