"""C++ text split into its comments and its code, by a small scanner.

Why a scanner and not a regular expression: ``"http://x"`` in a string is no comment, a
``/* ... */`` spans lines, and a ``//`` inside a block comment starts nothing. The scanner knows
string and character literals (with escapes), raw strings (``R"x(...)x"``), line and block
comments; that is all the code grade needs (commented-out code, the template's comment lines,
a comment-free text to compare). It never fails: an unterminated literal or comment runs to
the end of the file.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

__all__ = ["Comment", "code_only", "comments"]

_RAW = re.compile(r'R"([^()\\ ]{0,16})\(')


@dataclass(frozen=True, slots=True)
class Comment:
    """One line of a comment: where it is and what it says without its markers."""

    line: int
    """1-based line number."""
    text: str
    """The line's text, the comment markers (``//``, ``/*``, ``*/``, a leading ``*``) removed."""
    doc: bool
    """A documentation comment (``///``, ``//!``, ``/**``, ``/*!``): doxygen's, never code."""
    block: bool
    """Part of a ``/* */`` comment."""


def _scan(text: str) -> tuple[list[Comment], str]:
    out: list[Comment] = []
    code = list(text)
    i, n, line = 0, len(text), 1

    def blank(a: int, b: int) -> None:
        for k in range(a, b):
            if code[k] != "\n":
                code[k] = " "

    while i < n:
        ch = text[i]
        if ch == "\n":
            line += 1
            i += 1
        elif text.startswith("//", i):
            end = text.find("\n", i)
            end = n if end < 0 else end
            body = text[i + 2 : end]
            doc = body.startswith(("/", "!")) and not body.startswith("//")
            out.append(Comment(line, body.lstrip("/!").strip(), doc, False))
            blank(i, end)
            i = end
        elif text.startswith("/*", i):
            close = text.find("*/", i + 2)
            end = n if close < 0 else close + 2
            body = text[i + 2 : n if close < 0 else close]
            doc = body.startswith(("*", "!")) and not body.startswith("*/")
            for k, part in enumerate(body.split("\n")):
                part = part.strip()
                if k == 0:
                    part = part.lstrip("*!").strip()
                elif part.startswith("*"):
                    part = part[1:].strip()
                out.append(Comment(line + k, part, doc, True))
            line += body.count("\n")
            blank(i, end)
            i = end
        elif ch == "R" and (m := _RAW.match(text, i)):
            closing = ")" + m.group(1) + '"'
            end = text.find(closing, m.end())
            end = n if end < 0 else end + len(closing)
            line += text.count("\n", i, end)
            i = end
        elif ch in "\"'":
            k = i + 1
            while k < n and text[k] != ch and text[k] != "\n":
                k += 2 if text[k] == "\\" else 1
            i = min(k + 1, n)
        else:
            i += 1
    return out, "".join(code)


def comments(text: str) -> list[Comment]:
    """Every comment line of ``text``, in order (a block comment gives one per line)."""
    return _scan(text)[0]


def code_only(text: str) -> str:
    """``text`` with every comment blanked (spaces; newlines kept, so lines stay lines)."""
    return _scan(text)[1]
