"""The code rubric as data (TOML), and a package's metrics scored by it.

Why data: the course's code grade is the instructor's to change (a line's points, a
threshold), and each threshold has a source (the measured spread on a class, or the handout)
that a grader should be able to read beside it. The default rubric ships in the package
(``default_rubric.toml``, ENPM809Y's 60 points); ``usar code --rubric FILE`` takes another of
the same shape (docs/code-rubric.md).

A line whose metric was not measured (a tool missing, ``--compile`` not given) scores nothing
and counts for nothing: its ``points`` and ``measured`` are null, its note says why, and the
package's ``max_points`` leave it out, so a grade is never lowered by what was not looked at.
"""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

from usar_replay.core.errors import UsageError

__all__ = [
    "FORMAT", "KINDS", "Line", "Rubric", "Scored", "default_rubric", "load", "parse", "score"
]  # fmt: skip

FORMAT = "usar-code-rubric/1"
KINDS = ("true", "levels", "at_least", "at_most")


@dataclass(frozen=True, slots=True)
class Line:
    id: str
    title: str
    points: float
    metric: str
    kind: str
    full: float = 0.0
    zero: float = 0.0
    levels: tuple[tuple[str, float], ...] = ()
    source: str = ""

    @property
    def threshold(self) -> str:
        """The line's rule in words."""
        if self.kind == "true":
            return "true"
        if self.kind == "levels":
            return ", ".join(f"{k}: {v:g}" for k, v in self.levels)
        sign = ">=" if self.kind == "at_least" else "<="
        return f"full at {sign} {self.full:g}, none at {self.zero:g}"


@dataclass(frozen=True, slots=True)
class Rubric:
    name: str
    lines: tuple[Line, ...]
    grader: tuple[str, ...]
    source: str
    """Where it was read ("default" or the file)."""

    @property
    def max_points(self) -> float:
        return sum(line.points for line in self.lines)


@dataclass(frozen=True, slots=True)
class Scored:
    line: Line
    points: float | None
    measured: object
    evidence: str
    note: str


def _line(raw: Mapping[str, Any], where: str) -> Line:
    try:
        kind = str(raw["kind"])
        if kind not in KINDS:
            raise UsageError(f"{where}: kind {kind!r} is not one of {', '.join(KINDS)}")
        levels = tuple(sorted((str(k), float(v)) for k, v in dict(raw.get("levels", {})).items()))
        line = Line(
            id=str(raw["id"]),
            title=str(raw.get("title", raw["id"])),
            points=float(raw["points"]),
            metric=str(raw["metric"]),
            kind=kind,
            full=float(raw.get("full", 0.0)),
            zero=float(raw.get("zero", 0.0)),
            levels=levels,
            source=str(raw.get("source", "")),
        )
    except KeyError as err:
        raise UsageError(f"{where}: no {err.args[0]!r}; every line needs id, points, metric, "
                         "kind") from None  # fmt: skip
    except (TypeError, ValueError) as err:
        raise UsageError(f"{where}: {err}") from None
    if line.kind in ("at_least", "at_most") and line.full == line.zero:
        raise UsageError(f"{where}: full and zero are both {line.full:g}; make them differ")
    return line


def parse(text: str, source: str) -> Rubric:
    """A rubric from TOML text (``source``: where it came from, for messages)."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise UsageError(f"--rubric {source}: not TOML ({err})") from None
    if data.get("format") != FORMAT:
        raise UsageError(f"--rubric {source}: format must be {FORMAT!r}")
    raw_lines = data.get("line", [])
    if not isinstance(raw_lines, list) or not raw_lines:
        raise UsageError(f"--rubric {source}: no [[line]] tables")
    lines = tuple(_line(r, f"--rubric {source}: line {i + 1}") for i, r in enumerate(raw_lines))
    ids = [line.id for line in lines]
    if len(set(ids)) != len(ids):
        raise UsageError(f"--rubric {source}: a line id is used twice")
    grader = tuple(str(x) for x in data.get("grader", {}).get("items", []))
    return Rubric(str(data.get("name", source)), lines, grader, source)


def default_rubric() -> Rubric:
    text = resources.files("usar_replay.code").joinpath("default_rubric.toml").read_text()
    return parse(text, "default")


def load(path: str | None) -> Rubric:
    """The rubric at ``path`` (None: the default)."""
    if path is None:
        return default_rubric()
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        raise UsageError(f"--rubric {path}: cannot be read ({err}); give a TOML file") from None
    return parse(text, path)


def _share(line: Line, value: object) -> float | None:
    if value is None:
        return None
    if line.kind == "true":
        return 1.0 if value is True else 0.0
    if line.kind == "levels":
        return dict(line.levels).get(str(value), 0.0)
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    v = float(value)
    if line.kind == "at_least":
        frac = (v - line.zero) / (line.full - line.zero)
    else:
        frac = (line.zero - v) / (line.zero - line.full)
    return min(1.0, max(0.0, frac))


def score(
    rubric: Rubric,
    metrics: Mapping[str, object],
    evidence: Mapping[str, str],
    notes: Mapping[str, str],
    failed: frozenset[str] = frozenset(),
) -> list[Scored]:
    """Each line of ``rubric`` scored on ``metrics`` (an unknown or None metric: not judged,
    the note says why). A metric in ``failed`` could not be measured because of the team's
    files (a tool past its limits on them, or failing on them): its lines score 0, never
    ``null``, so a file made to stop a tool cannot take a line out of the maximum."""
    out = []
    for line in rubric.lines:
        value = metrics.get(line.metric)
        share = 0.0 if line.metric in failed and value is None else _share(line, value)
        note = notes.get(line.metric, "")
        if share is None and not note:
            note = f"{line.metric} was not measured"
        pts = None if share is None else round(line.points * share, 2)
        out.append(Scored(line, pts, value, evidence.get(line.metric, ""), note))
    return out
