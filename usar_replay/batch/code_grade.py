"""``usar batch --code``: the code submission graded beside the demo, for the class's table,
CSV, page and Gradescope.

Why a flag: the code grade costs about half a second a team and needs doxygen, cppcheck and
clang-format; a batch that only regrades demos should not pay for it or need them. With it,
every team folder that holds a catkin package is graded as ``usar code`` grades it
(:mod:`usar_replay.code.classgrade`: same discovery, rubric, template and similarity), and
``OUT/code.json`` (``usar-code/1``), ``OUT/code.csv`` and ``OUT/code.html`` (similar pairs'
passages side by side) are written. A team without a package (a Python mission) has no code
grade. Each team's :class:`CodeCell` is what the class's reports show: its own points and
maximum (a separate Gradescope test with its own ``max_score``), the rubric lines as text, and
the teams it is similar to (for a person; never points). Each team is graded under its budget
(:mod:`usar_replay.code.budget`: tool calls, PDFs looked at, wall time), so no team's files hold
the other teams' results for longer than that (issue 50: six long PDFs held a batch 96 s).

Why the demo's build for "builds without warnings": the batch has built every package already
(catkin_make, ``-Wall -Wextra`` added), so each ROS 1 run's record keeps what that build's
compiler said of the package's own files (:func:`compiler_record`, ``compiler`` in
``<world>.run.json``; a cached build's output is kept with the cache entry, so a hit says the
same) and the code grade scores it (:func:`demo_builds`): ``compiles``, ``builds_clean`` and
``compiler_warnings`` are measured, the code grade is out of the rubric's full 60, and no file
is compiled twice. A team no run built (its start unclear, a run usar could not record) has
them unmeasured, said.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from usar_replay.code.compile import Compiled

if TYPE_CHECKING:
    from usar_replay.pipeline.record import BuildLog

__all__ = [
    "CODE_CSV",
    "CODE_HTML",
    "CODE_JSON",
    "COMPILER",
    "CodeCell",
    "cells_from_json",
    "compiler_record",
    "demo_builds",
    "grade_code",
]

CODE_JSON = "code.json"
CODE_CSV = "code.csv"
CODE_HTML = "code.html"
COMPILER = "compiler"
"""A ROS 1 run record's key for what its build's compiler said (:func:`compiler_record`)."""
_NOT_BUILT = Compiled(
    None, 0, "", "not measured: no run of the demo built the package (see its runs' outcomes)"
)
_REASON_CHARS = 200


@dataclass(frozen=True, slots=True)
class CodeCell:
    points: float
    max_points: float
    lines: tuple[str, ...]
    """The rubric's lines for a person (``6/6 classes = 2  evidence``)."""
    similar: tuple[str, ...] = ()
    """``team (score)`` of each team listed as similar."""


def _line(raw: dict[str, Any]) -> str:
    pts = "-" if raw.get("points") is None else f"{float(raw['points']):.4g}"
    shown = "" if raw.get("measured") is None else f" = {raw['measured']}"
    tail = raw.get("evidence") or raw.get("note") or ""
    return f"{pts}/{float(raw.get('max_points', 0)):.4g} {raw.get('id', '')}{shown}  {tail}"


def cells_from_json(doc: dict[str, Any] | None) -> dict[str, CodeCell]:
    """Each team's cell from a ``usar-code/1`` document (``{}`` for anything else)."""
    if not doc or doc.get("format") != "usar-code/1":
        return {}
    similar: dict[str, list[str]] = {}
    for p in doc.get("similar", []):
        a, b, score = str(p.get("a")), str(p.get("b")), float(p.get("score", 0))
        similar.setdefault(a, []).append(f"{b} ({score:.2f})")
        similar.setdefault(b, []).append(f"{a} ({score:.2f})")
    out = {}
    for pkg in doc.get("packages", []):
        team = str(pkg.get("team", ""))
        out[team] = CodeCell(
            float(pkg.get("points", 0.0)),
            float(pkg.get("max_points", 0.0)),
            tuple(_line(x) for x in pkg.get("lines", [])),
            tuple(sorted(similar.get(team, []))),
        )
    return out


def compiler_record(build: str, log: BuildLog | None, reason: str) -> dict[str, Any] | None:
    """What a ROS 1 run's record keeps of its package's build for the code grade: the
    compiler's lines read by :func:`usar_replay.code.compile.from_build` (``build``: the
    run's build note, ``failed`` for one that failed before catkin_make could run, ``reason``
    its outcome's words then); None when nothing was built (the run never got that far)."""
    from usar_replay.code.compile import from_build
    from usar_replay.core.safe_text import safe_line

    if log is not None:
        built = from_build(log.output, log.root, log.failed, log.flags)
    elif build == "failed":
        said = safe_line(reason)[:_REASON_CHARS]
        built = Compiled(False, 0, "", note=f"the demo's build failed: {said}")
    else:
        return None
    return asdict(built)


def _compiled(raw: object) -> Compiled | None:
    """A record's ``compiler`` entry back, or None for anything else (a hand-edited file)."""
    if not isinstance(raw, dict):
        return None
    compiles, warnings = raw.get("compiles"), raw.get("warnings")
    texts = [raw.get(k, "") for k in ("where", "problem", "note")]
    if compiles not in (True, False, None) or isinstance(warnings, bool):
        return None
    if not isinstance(warnings, int) or not all(isinstance(t, str) for t in texts):
        return None
    return Compiled(compiles, warnings, *texts)


def demo_builds(out_root: Path, teams: Sequence[str], worlds: Sequence[str]) -> dict[str, Compiled]:
    """Each team's build as its runs' records in ``out_root`` keep it (:func:`compiler_record`;
    the first of ``worlds`` by name whose record has one: the same package gives the same
    answer in every world); a team none of whose records has one is not in it."""
    from usar_replay.batch.plan import RUN_FORMAT, read_json

    out: dict[str, Compiled] = {}
    for team in teams:
        for world in sorted(worlds):
            rec = read_json(out_root / team / f"{world}.run.json")
            if rec is None or rec.get("format") != RUN_FORMAT:
                continue
            built = _compiled(rec.get(COMPILER))
            if built is not None:
                out[team] = built
                break
    return out


def grade_code(
    teams: Sequence[tuple[str, Path]],
    out_root: Path,
    template: str | None,
    jobs: int = 1,
    builds: Mapping[str, Compiled] | None = None,
) -> dict[str, CodeCell]:
    """Grade the code of every team whose folder holds a package; write ``code.json``,
    ``code.csv`` and ``code.html`` into ``out_root``; each graded team's cell. ``builds``:
    each team's build as the demo ran it (:func:`demo_builds`; a graded team missing from it
    has the build's lines unmeasured, said); None: not measured at all (as ``usar code``
    without ``--compile``)."""
    from usar_replay.code import classgrade, output, rubric
    from usar_replay.code import template as tmpl
    from usar_replay.code.html import pairs_html
    from usar_replay.core.outfiles import write_text
    from usar_replay.ros1.building.workspace import find_package

    def has_package(folder: Path) -> bool:
        try:
            find_package(folder)
        except Exception:  # noqa: BLE001 (no package, several, unreadable: no code grade)
            return False
        return True

    graded = [(team, f) for team, f in teams if f.is_dir() and has_package(f)]
    if not graded:
        return {}
    rub = rubric.default_rubric()
    base = tmpl.read_template(template) if template else tmpl.NO_TEMPLATE
    built = None if builds is None else {t: builds.get(t, _NOT_BUILT) for t, _ in graded}
    done = classgrade.grade_teams(graded, rub, base, jobs=jobs, built=built)
    doc = output.to_json(done.grades, done.similar, rubric=rub.name, template=template,
                         threshold=done.threshold)  # fmt: skip
    write_text(out_root / CODE_JSON, doc, overwrite=True)
    write_text(out_root / CODE_CSV, output.to_csv(done.grades, done.similar), overwrite=True)
    write_text(out_root / CODE_HTML, pairs_html(done.similar, done.threshold), overwrite=True)
    parsed: dict[str, Any] = json.loads(doc)
    return cells_from_json(parsed)
