"""The course template, as boilerplate: what every team was given never counts as theirs.

Why: every team starts from the same package (the course's ``final_project``: a ``main.cpp``
with ``broadcast()``, ``listen()``, a long ``main()`` and commented-out lines of its own), so
without it a commented-out line, an unused function or a shared passage would be charged to
every team alike. On a class, winnowing with the template as boilerplate scored three
near-copies 1.0 and every honest pair at most .46; without it, honest pairs reached .65.

:func:`read_template` reads a template folder as a team's is read (same walk, same limits);
:data:`NO_TEMPLATE` is the empty one, when ``--template`` is not given (then the output says
that the template's code counts as the team's).
"""

from __future__ import annotations

import hashlib
import os
import re
from dataclasses import dataclass
from pathlib import PurePosixPath

from usar_replay.code.comments import looks_like_code, normal
from usar_replay.code.cxx import code_only, comments
from usar_replay.code.doxygen import symbols
from usar_replay.code.sources import Source, read_submission
from usar_replay.core.folder_walk import shown, stream

__all__ = ["NO_TEMPLATE", "Template", "function_names", "read_template"]

_DEFINITION = re.compile(
    r"\b([A-Za-z_]\w*)\s*\([^;{}()]*(\([^;{}()]*\)[^;{}()]*)*\)\s*(const\s*)?\{"
)
_NOT_FUNCTIONS = frozenset({"if", "for", "while", "switch", "catch", "return", "sizeof"})


@dataclass(frozen=True, slots=True)
class Template:
    sources: tuple[Source, ...]
    comment_lines: frozenset[str]
    """Its commented-out code lines, whitespace removed (:func:`~.comments.normal`)."""
    names: frozenset[str]
    """The functions it defines, qualified as doxygen names them (``listen``,
    ``Explorer::step``); by a definition's short name when doxygen is not installed."""
    pdf_sha256: frozenset[str]
    """Its PDFs (the course's handout): never a team's report."""
    path: str = ""


NO_TEMPLATE = Template((), frozenset(), frozenset(), frozenset())


def function_names(text: str) -> set[str]:
    """The short names of the functions ``text`` defines (a definition: a name, its
    parameters, then a body's ``{``), comments and strings aside."""
    found = set()
    for m in _DEFINITION.finditer(code_only(text)):
        if m.group(1) not in _NOT_FUNCTIONS:
            found.add(m.group(1))
    return found


def read_template(path: str | os.PathLike[str]) -> Template:
    """The template at ``path`` (a package folder, or a folder holding one)."""
    sub = read_submission(path, "template", need_package=False)
    lines = frozenset(
        normal(c.text)
        for s in sub.sources
        for c in comments(s.text)
        if not c.doc and looks_like_code(c.text)
    )
    found = symbols(sub.sources)
    if found.problem:
        names = frozenset(n for s in sub.sources for n in function_names(s.text))
    else:
        names = frozenset(s.name for s in found.items if s.kind == "function")
    pdfs = set()
    for e in sub.entries:
        if PurePosixPath(shown(e.rel)).suffix.lower() == ".pdf" and e.link is None:
            h = hashlib.sha256()
            stream(e, h.update)
            pdfs.add(h.hexdigest())
    return Template(sub.sources, lines, names, frozenset(pdfs), str(path))
