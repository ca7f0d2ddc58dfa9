"""Does the committed Doxygen HTML document *this* package's current sources?

Why more than "``doc/html`` exists": on issue 45's 21 packages one team's committed ``doc/html`` and
Doxyfile documented another team's sources (its history: a clone of another team's repository,
then its C++ replaced). A files-exist check gives that team the points. Here the HTML is read
(its file names, capped bytes of its text) and must name what the package holds now: at least
:data:`SHARE` of the package's C++ files by doxygen's page names (``explorer_8cpp.html``:
``explorer.cpp``) and at least :data:`SHARE` of its own classes' and functions' names in its
text. Stale HTML (made before half the code was written) or someone else's fails the same test,
and the line says which names are missing.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import PurePosixPath

from usar_replay.code.sources import Submission, read_text

__all__ = ["SHARE", "DocsOwn", "docs_own", "html_files"]

SHARE = 0.8
"""What share of the current files and names the HTML must show."""
_HTML_BYTES = 4 * 1024 * 1024
"""Bytes of one HTML page read."""
_PAGE = re.compile(r"^(.+?)_8([a-z]+)(_source)?\.html$")


@dataclass(frozen=True, slots=True)
class DocsOwn:
    own: bool | None
    """True: it documents these sources; False: stale or another's; None: no HTML in doc/."""
    pages: int
    """HTML pages found under the package's ``doc/``."""
    files_share: float
    names_share: float
    evidence: str
    """Where (``doc/html/index.html``) and what is missing, for the grader."""


def html_files(sub: Submission) -> list[str]:
    """The HTML pages under the package's ``doc/`` (relative to the package), sorted."""
    return sorted(
        f for f in sub.package_files() if f.startswith("doc/") and f.lower().endswith(".html")
    )


_ESCAPES = {"_": "_", "8": ".", "1": ":", "2": "/", "3": "<", "4": ">", "5": "*", "6": "&",
            "7": "|", "9": "!"}  # fmt: skip


def _unescape(stem: str) -> str:
    """doxygen's file-name escaping undone: ``__`` ``_``, ``_8`` ``.``; with
    ``CASE_SENSE_NAMES = NO``, ``_r`` is ``R`` (lower-cased here anyway)."""
    out, i = [], 0
    while i < len(stem):
        ch = stem[i]
        if ch == "_" and i + 1 < len(stem):
            nxt = stem[i + 1]
            out.append(_ESCAPES.get(nxt, nxt))
            i += 2
        else:
            out.append(ch)
            i += 1
    return "".join(out).lower()


def _page_source(name: str) -> str | None:
    """``explorer_8cpp.html`` -> ``explorer.cpp`` (doxygen's page of a file; ``_robot_8h.html``,
    as a case-insensitive doxygen names ``Robot.h``, -> ``robot.h``)."""
    m = _PAGE.match(name)
    if not m:
        return None
    return _unescape(m.group(1)) + "." + m.group(2)


def _short(name: str) -> str:
    return name.split("::")[-1]


def docs_own(sub: Submission, own_names: Iterable[str]) -> DocsOwn:
    """The check of the module's docstring; ``own_names``: the package's own classes and
    functions (qualified)."""
    pages = html_files(sub)
    if not pages:
        return DocsOwn(None, 0, 0.0, 0.0, "no HTML under doc/")
    documented = {_page_source(PurePosixPath(p).name) for p in pages} - {None}
    current = sorted({PurePosixPath(s.rel).name.lower() for s in sub.sources})
    files_hit = [f for f in current if f in documented]
    text_parts: list[str] = []
    for page in pages:
        rel = f"{sub.package_prefix}/{page}" if sub.package_prefix else page
        entry = sub.entry(rel)
        if entry is None or entry.link is not None:
            continue
        text, _ = read_text(entry, _HTML_BYTES)
        if text is not None:
            text_parts.append(text)
    words = set(re.findall(r"[A-Za-z_]\w*", "\n".join(text_parts)))
    names = sorted(
        {_short(n) for n in own_names if len(_short(n)) >= 3 and _short(n) != "main"}
    )
    names_hit = [n for n in names if n in words]
    files_share = len(files_hit) / len(current) if current else 0.0
    names_share = len(names_hit) / len(names) if names else 1.0
    own = files_share >= SHARE and names_share >= SHARE
    where = os.path.dirname(pages[0]) or "doc"
    gone_files = [f for f in current if f not in documented]
    gone_names = [n for n in names if n not in words]
    said = f"{where}: {len(pages)} pages, {len(files_hit)}/{len(current)} files"
    said += f", {len(names_hit)}/{len(names)} names"
    if not own:
        lost = gone_files[:3] + gone_names[:3]
        said += "; not documented there: " + ", ".join(lost)
    return DocsOwn(own, len(pages), round(files_share, 3), round(names_share, 3), said)
