"""Commented-out code: how many lines, the largest block, where.

Why: the handout says "Do not leave big chunks of commented code in your program", and on issue 45's
21 packages commented-out code spread from 0 to 51 lines, spot checks all true positives
(a leftover ``// explorer_client.waitForResult();``). A comment line is code when it reads as
C++ (:func:`looks_like_code`): it ends with ``;``, ``{`` or ``}``, or is a preprocessor line,
a control statement or a call. Documentation comments (``///``, ``/** */``) are never code:
doxygen shows their examples. Lines that are the course template's own comments
(``template_lines``, whitespace ignored) are the template's, not the team's, and do not count.
Code switched off with ``#if 0 ... #endif`` counts as well: it is a comment by other means.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from dataclasses import dataclass

from usar_replay.code.cxx import code_only, comments
from usar_replay.code.sources import Source

__all__ = ["CommentedOut", "commented_out", "if_zero_blocks", "looks_like_code", "normal"]

_ENDS = re.compile(r"(;|\{|\}|\};|\)\s*;?)\s*(//.*)?$")
_STARTS = re.compile(
    r"^(#\s*(include|define|if|endif|ifdef|ifndef|else|pragma)\b|"
    r"(if|for|while|switch|return|else|do|case|break|continue|auto|const|static|"
    r"std::|ros::|int|double|float|bool|void|char|unsigned|size_t)\b)"
)
_CALL = re.compile(r"^[A-Za-z_][\w:.<>\[\]\->]*\s*(\(.*\)|=\s*[^=].*)\s*;?$")
_PROSE_END = re.compile(r"[.?!:]$")
_BRACES = frozenset({"{", "}", "};", "});"})


def normal(text: str) -> str:
    """A comment line as compared with the template's: whitespace removed."""
    return "".join(text.split())


def looks_like_code(text: str) -> bool:
    """Does one comment line (markers removed) read as C++?"""
    t = text.strip()
    if t in _BRACES:
        return True  # a lone brace: code only next to other code (commented_out checks)
    if len(t) < 2 or (_PROSE_END.search(t) and not t.endswith("::")):
        return False
    if _ENDS.search(t) and any(c in t for c in "();={}"):
        return True
    if _STARTS.match(t) and any(c in t for c in "();=<{"):
        return True
    return bool(_CALL.match(t)) and "(" in t and " " not in t.split("(")[0].strip()


_IF0 = re.compile(r"^\s*#\s*if\s+(0|false)\b")
_IF = re.compile(r"^\s*#\s*if(n?def)?\b")
_ENDIF = re.compile(r"^\s*#\s*endif\b")


def if_zero_blocks(text: str) -> list[tuple[int, int]]:
    """(first line, lines) of each ``#if 0 ... #endif`` block's body: code switched off by the
    preprocessor is commented-out code too (nested ``#if``s inside it are followed)."""
    out: list[tuple[int, int]] = []
    depth, start = 0, 0
    for number, line in enumerate(code_only(text).split("\n"), 1):
        if depth == 0:
            if _IF0.match(line):
                depth, start = 1, number
            continue
        if _IF.match(line):
            depth += 1
        elif _ENDIF.match(line):
            depth -= 1
            if depth == 0 and number - start - 1 > 0:
                out.append((start + 1, number - start - 1))
    return out


@dataclass(frozen=True, slots=True)
class CommentedOut:
    lines: int
    """Lines of commented-out code, the template's left out."""
    largest: int
    """Lines of the largest block (consecutive lines of commented-out code)."""
    where: str
    """``file:line`` of the largest block ('' when none)."""
    blocks: tuple[tuple[str, int, int], ...]
    """Every block as (file, first line, lines), largest first."""


def commented_out(
    sources: Iterable[Source], template_lines: frozenset[str] = frozenset()
) -> CommentedOut:
    """The commented-out code of ``sources`` (see the module's docstring)."""
    blocks: list[tuple[str, int, int]] = []
    total = 0
    for src in sources:
        run_start, run_len, last = 0, 0, -10
        for c in comments(src.text):
            if c.doc or not looks_like_code(c.text) or normal(c.text) in template_lines:
                continue
            if c.text.strip() in _BRACES and c.line != last + 1:
                continue  # a brace alone is code when it closes (or opens) commented code
            total += 1
            if c.line == last + 1:
                run_len += 1
            else:
                if run_len:
                    blocks.append((src.rel, run_start, run_len))
                run_start, run_len = c.line, 1
            last = c.line
        if run_len:
            blocks.append((src.rel, run_start, run_len))
        for first, n in if_zero_blocks(src.text):
            blocks.append((src.rel, first, n))
            total += n
    blocks.sort(key=lambda b: (-b[2], b[0], b[1]))
    largest = blocks[0] if blocks else None
    return CommentedOut(
        lines=total,
        largest=largest[2] if largest else 0,
        where=f"{largest[0]}:{largest[1]}" if largest else "",
        blocks=tuple(blocks),
    )
