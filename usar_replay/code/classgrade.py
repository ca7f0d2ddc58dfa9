"""A class's code graded: the teams found in the paths given, each graded, pairs compared.

Why here: ``usar code PKG...`` and ``usar code DIR`` (a folder of team folders, as ``usar
batch`` takes) grade the same way, and ``usar batch --code`` reuses it. A path that is (or holds
exactly one) catkin package is one team, found as ``--ros1`` finds it; a path that holds several
is a class folder (two or more of its sub-folders hold a package), each non-hidden sub-folder
a team. A team whose folder cannot be read (a
FIFO, a link out, a file over the caps, no package) is that team's verdict (``unreadable``,
every line 0, the reason said), never the end of the class.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, replace
from pathlib import Path

from usar_replay.code import similarity
from usar_replay.code.compile import Compiled
from usar_replay.code.grade import Options, PackageGrade, grade, refused
from usar_replay.code.rubric import Rubric
from usar_replay.code.sources import Submission, read_submission
from usar_replay.code.template import NO_TEMPLATE, Template
from usar_replay.core.errors import NoPackage, SeveralPackages, UsageError, UsarError
from usar_replay.core.folder_walk import shown
from usar_replay.ros1.building.workspace import find_package

__all__ = ["ClassCode", "grade_class", "grade_teams", "teams"]


@dataclass(frozen=True, slots=True)
class ClassCode:
    grades: tuple[PackageGrade, ...]
    similar: tuple[similarity.Pair, ...]
    threshold: float


def _sub_folders(path: Path) -> list[Path]:
    try:
        with os.scandir(path) as it:
            return sorted(
                Path(e.path) for e in it
                if e.is_dir(follow_symlinks=False) and not e.name.startswith((".", "_"))
            )  # fmt: skip
    except OSError as err:
        raise UsageError(f"{path}: cannot be read ({err.strerror})") from None


def _holds_package(folder: Path) -> bool:
    try:
        find_package(folder)
    except SeveralPackages:
        return True
    except UsarError:
        return False
    return True


def teams(paths: Sequence[str]) -> list[tuple[str, Path]]:
    """(team name, folder) of every team in ``paths``, sorted by name (see the docstring)."""
    out: dict[str, Path] = {}
    for raw in paths:
        path = Path(raw)
        if not path.is_dir():
            raise UsageError(f"{raw}: no such folder; give package folders or a class folder")
        subs = [] if (path / "package.xml").is_file() else _sub_folders(path)
        if sum(1 for s in subs if _holds_package(s)) >= 2:
            found = subs  # a class folder: each sub-folder is a team (one without: its verdict)
        else:
            try:
                find_package(path)
                found = [path]
            except SeveralPackages:
                found = subs
            except NoPackage:
                found = subs if len(paths) == 1 else [path]
        if not found:
            raise UsageError(f"{raw}: no catkin package in it; give package folders")
        for folder in found:
            name = shown(folder.resolve().name)
            if name in out and out[name] != folder:
                name = f"{name}-{len(out)}"
            out[name] = folder
    return sorted(out.items())


def _one(team: str, folder: Path, rubric: Rubric, template: Template, options: Options
         ) -> tuple[PackageGrade, Submission | None]:  # fmt: skip
    try:
        sub = read_submission(folder, team)
    except UsarError as err:
        return refused(team, str(folder), str(err).removeprefix("--ros1 "), rubric), None
    return grade(sub, rubric, template, options), sub


def grade_class(
    paths: Sequence[str],
    rubric: Rubric,
    template: Template = NO_TEMPLATE,
    options: Options | None = None,
    *,
    jobs: int = 1,
    threshold: float = similarity.THRESHOLD,
) -> ClassCode:
    """Every team of ``paths`` graded (``jobs`` at a time), and the pairs of them whose own
    code scores ``threshold`` or more."""
    return grade_teams(teams(paths), rubric, template, options, jobs=jobs, threshold=threshold)


def grade_teams(
    found: Sequence[tuple[str, Path]],
    rubric: Rubric,
    template: Template = NO_TEMPLATE,
    options: Options | None = None,
    *,
    jobs: int = 1,
    threshold: float = similarity.THRESHOLD,
    built: Mapping[str, Compiled] | None = None,
) -> ClassCode:
    """:func:`grade_class` of teams already named (``usar batch``'s, by its own names);
    ``built``: each team's own build, as the batch's demo ran it (:attr:`Options.built`)."""
    opts = options or Options()
    builds = built or {}

    def one(team: str, folder: Path) -> tuple[PackageGrade, Submission | None]:
        mine = replace(opts, built=builds[team]) if team in builds else opts
        return _one(team, folder, rubric, template, mine)

    with ThreadPoolExecutor(max(1, jobs)) as pool:
        done = list(pool.map(lambda t: one(*t), found))
    pairs: list[similarity.Pair] = []
    subs = [s for _, s in done if s is not None]
    if len(subs) > 1:
        bp = similarity.boilerplate(template.sources)
        prints = [similarity.prints(s.name, s.sources, bp) for s in subs]
        pairs = similarity.similar(prints, threshold)
    return ClassCode(tuple(g for g, _ in done), tuple(pairs), threshold)
