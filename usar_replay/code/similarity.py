"""Copies across a class: winnowing (as MOSS) over each team's own code, normalised, the
template as boilerplate.

Why winnowing over a normalised stream: fingerprints of the token stream are blind to what a
copier changes first only when that stream no longer holds it. :mod:`usar_replay.code.normalise`
makes C++ one symbol per token with whitespace, comments, empty statements, braces, redundant
parentheses, ``this->``, identifier names, literal values and specifiers gone, so ``; ;`` after
every statement, renamed variables and changed constants leave the stream as it was (a ``; ;``
copy scored .393 with copydetect's own filter, which kept punctuation: issue 50); and
fingerprints are a set, so reordered functions do not hide a copy either. copydetect's winnowing
is used (its k-gram hash is not, see :func:`_kgram_hashes`). Every team starts from the course
template, so its fingerprints are boilerplate and never count.

Measured (docs/code-rubric.md, "Copies across a class"): on 16 public Fall 2021 packages, every
honest pair at most .391 with the template as boilerplate; copies of each of them with ``; ;``
1.000, renamed .939 or more, functions reordered .971 or more, all three .920 or more, a dummy
statement after every third .803 or more. K = 20 symbols is the k-gram that keeps both apart
best (25: honest .369, but dummy statements every third .675; 15: honest .491).

A pair's score is the larger of the two shares (of each team's fingerprinted tokens, the share
found in the other's): a team that copied another's whole package into a larger one still
scores high. Pairs at or above :data:`THRESHOLD` are listed for a person to review, with the
matching passages; a pair is never points.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

from usar_replay.code.normalise import normalise
from usar_replay.code.sources import Source

__all__ = ["K", "THRESHOLD", "WINDOW", "Pair", "Passage", "Prints", "boilerplate", "prints",
           "similar"]  # fmt: skip

K = 20
"""Symbols (tokens) of a k-gram of the normalised stream (see the docstring for the measure)."""
WINDOW = 6
"""Winnowing window: any match of K + WINDOW - 1 tokens is found (copydetect's default)."""
THRESHOLD = 0.6
"""A pair at or above this is listed (honest pairs measured at most .391, cosmetic copies .80
or more)."""
MIN_TOKENS = 50
"""A team with fewer fingerprinted tokens of its own is compared with nobody (nothing of its
own to copy)."""


@dataclass(frozen=True, slots=True)
class Passage:
    a: str
    """``file:first-last`` in team a's sources."""
    b: str
    a_text: str
    b_text: str


@dataclass(frozen=True, slots=True)
class Pair:
    a: str
    b: str
    score: float
    passages: tuple[Passage, ...] = ()


@dataclass(slots=True)
class Prints:
    """One team's fingerprints and the text they came from."""

    team: str
    text: str
    starts: tuple[tuple[int, str], ...]
    """Where each file starts in :attr:`text`: (offset, relative path)."""
    fingerprint: _Fingerprint

    @property
    def tokens(self) -> int:
        return int(self.fingerprint.token_coverage)


def _joined(sources: Iterable[Source]) -> tuple[str, tuple[tuple[int, str], ...]]:
    parts: list[str] = []
    starts: list[tuple[int, str]] = []
    at = 0
    for s in sorted(sources, key=lambda s: s.rel):
        starts.append((at, s.rel))
        text = s.text if s.text.endswith("\n") else s.text + "\n"
        parts.append(text)
        at += len(text)
    return "".join(parts), tuple(starts)


@dataclass(slots=True)
class _Fingerprint:
    """What copydetect's ``compare_files`` reads of a fingerprint (its ``CodeFingerprint``'s
    attributes), made with a hash that is the same in every process."""

    k: int
    filtered_code: str
    offsets: Any
    hashes: set[int]
    hash_idx: dict[int, list[int]]
    token_coverage: int
    starts: tuple[int, ...] = ()
    """Each stream symbol's first character in the joined text."""
    ends: tuple[int, ...] = ()


def _kgram_hashes(text: str, k: int) -> Any:
    """A polynomial hash of every k-gram of ``text``, as int64 (numpy, wrapping arithmetic).

    Why not copydetect's own: it hashes with Python's ``hash()``, which is salted per process
    (``PYTHONHASHSEED``), so winnowing kept other fingerprints in each run and a pair scored
    .89 in one run and .92 in the next. This one is the same everywhere."""
    import numpy as np

    codes = np.frombuffer(text.encode("utf-32-le"), dtype=np.uint32).astype(np.uint64)
    n = len(codes) - k + 1
    if n <= 0:
        return np.array([], dtype=np.int64)
    h = np.zeros(n, dtype=np.uint64)
    base = np.uint64(1_000_003)
    with np.errstate(over="ignore"):
        for j in range(k):
            h = h * base + codes[j : j + n]
    return h.view(np.int64)


def _fingerprint(text: str, k: int, window: int, bp: Any = None) -> _Fingerprint:
    """The fingerprint of ``text`` as copydetect makes it (its winnowing; boilerplate
    removed), over :mod:`usar_replay.code.normalise`'s stream (one symbol per token), with
    :func:`_kgram_hashes`."""
    import numpy as np
    from copydetect.utils import get_token_coverage, winnow

    stream = normalise(text)
    hashes, idx = winnow(_kgram_hashes(stream.text, k), window, remove_duplicates=False)
    if bp is not None and len(bp) > 0:
        keep = ~np.isin(hashes, bp)
        hashes, idx = hashes[keep], idx[keep]
    by_hash: dict[int, list[int]] = {}
    for value, i in zip(hashes.tolist(), idx.tolist(), strict=True):
        by_hash.setdefault(int(value), []).append(int(i))
    coverage = int(get_token_coverage(by_hash, k, len(stream.text)))
    # no offsets: copydetect's slices stay in the stream's places; _passages maps them back
    return _Fingerprint(
        k, stream.text, np.array([]), set(by_hash), by_hash, coverage, stream.starts, stream.ends
    )


def boilerplate(template: Iterable[Source]) -> Any:
    """The template's every k-gram hash (window 1, as copydetect takes boilerplate)."""
    import numpy as np

    text, _ = _joined(template)
    if not text.strip():
        return np.array([], dtype=np.int64)
    return np.unique(np.array(sorted(_fingerprint(text, K, 1).hashes), dtype=np.int64))


def prints(team: str, sources: Iterable[Source], bp: Any = None) -> Prints:
    """``team``'s fingerprints, its sources joined in path order, boilerplate removed."""
    text, starts = _joined(sources)
    return Prints(team, text, starts, _fingerprint(text, K, WINDOW, bp))


def _where(p: Prints, start: int, end: int) -> tuple[str, str]:
    """(``file:first-last``, the passage's text) of characters ``start:end`` of ``p.text``."""
    rel, base = p.starts[0][1], 0
    for off, name in p.starts:
        if off <= start:
            rel, base = name, off
    first = p.text.count("\n", base, start) + 1
    last = first + p.text.count("\n", start, max(start, end - 1))
    return f"{rel}:{first}-{last}", p.text[start:end]


def _text_span(p: Prints, first: int, last: int) -> tuple[int, int]:
    """Stream symbols ``first:last`` of ``p`` as characters of its text."""
    fp = p.fingerprint
    if not fp.starts:
        return 0, 0
    first = min(max(first, 0), len(fp.starts) - 1)
    last = min(max(last, first + 1), len(fp.ends))
    return fp.starts[first], fp.ends[last - 1]


def _passages(a: Prints, b: Prints, slices: tuple[Any, Any], most: int = 6) -> tuple[Passage, ...]:
    sa, sb = slices
    if len(sa) == 0 or len(sb) == 0:
        return ()
    pa = sorted(zip(sa[0].tolist(), sa[1].tolist(), strict=True), key=lambda s: s[0] - s[1])
    pb = sorted(zip(sb[0].tolist(), sb[1].tolist(), strict=True), key=lambda s: s[0] - s[1])
    out = []
    for (a0, a1), (b0, b1) in zip(pa[:most], pb[:most], strict=False):
        wa, ta = _where(a, *_text_span(a, int(a0), int(a1)))
        wb, tb = _where(b, *_text_span(b, int(b0), int(b1)))
        out.append(Passage(wa, wb, ta[:4000], tb[:4000]))
    return tuple(out)


def similar(teams: Sequence[Prints], threshold: float = THRESHOLD) -> list[Pair]:
    """Every pair of ``teams`` scoring at or above ``threshold``, highest first (then by
    names), each with its longest matching passages."""
    from copydetect import compare_files

    out: list[Pair] = []
    ordered = sorted(teams, key=lambda t: t.team)
    for i, a in enumerate(ordered):
        if a.tokens < MIN_TOKENS:
            continue
        for b in ordered[i + 1 :]:
            if b.tokens < MIN_TOKENS:
                continue
            _, (s1, s2), slices = compare_files(a.fingerprint, b.fingerprint)
            score = round(float(max(s1, s2)), 3)
            if score >= threshold:
                out.append(Pair(a.team, b.team, score, _passages(a, b, slices)))
    out.sort(key=lambda p: (-p.score, p.a, p.b))
    return out
