"""A class's code graded: the teams found in the paths given, each graded, pairs compared.

Why here: ``usar code PKG...`` and ``usar code DIR`` (a folder of team folders, as ``usar
batch`` takes) grade the same way, and ``usar batch --code`` reuses it. A path that is (or holds
exactly one) catkin package is one team, found as ``--ros1`` finds it; a path that holds several
is a class folder (two or more of its sub-folders hold a package), each non-hidden sub-folder
a team. A team whose folder cannot be read (a
FIFO, a link out, a file over the caps, no package) is that team's verdict (``unreadable``,
every line 0, the reason said), never the end of the class. A class folder's entry that is a
link to a folder is never read through (it could lead anywhere: ``usar batch`` refuses it in
the same words, :func:`usar_replay.core.folder_walk.linked`): that team's verdict, or, when
every team is one, a usage error saying so; a path given on the command line is the
grader's own and is read where it leads.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, replace
from pathlib import Path

from usar_replay.code import budget, similarity, tools
from usar_replay.code.compile import Compiled
from usar_replay.code.grade import Options, PackageGrade, grade, refused
from usar_replay.code.rubric import Rubric
from usar_replay.code.sources import Submission, read_submission
from usar_replay.code.template import NO_TEMPLATE, Template
from usar_replay.core.errors import NoPackage, SeveralPackages, UsageError, UsarError
from usar_replay.core.folder_walk import linked, shown
from usar_replay.ros1.building.workspace import find_package

__all__ = ["ClassCode", "grade_class", "grade_teams", "spent_line", "teams"]


@dataclass(frozen=True, slots=True)
class ClassCode:
    grades: tuple[PackageGrade, ...]
    similar: tuple[similarity.Pair, ...]
    threshold: float


def _sub_folders(path: Path) -> tuple[list[Path], list[Path]]:
    """The real sub-folders of ``path`` not starting with ``.`` or ``_``, and its entries of
    those names that are links to folders (never looked into)."""
    try:
        with os.scandir(path) as it:
            found = [e for e in it if not e.name.startswith((".", "_")) and e.is_dir()]
    except OSError as err:
        raise UsageError(f"{path}: cannot be read ({err.strerror})") from None
    real = sorted(Path(e.path) for e in found if not e.is_symlink())
    return real, sorted(Path(e.path) for e in found if e.is_symlink())


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
        if path.is_symlink():  # the grader's own path: read where it leads
            path = path.resolve()
        subs, links = ([], []) if (path / "package.xml").is_file() else _sub_folders(path)
        if sum(1 for s in subs if _holds_package(s)) >= 2:
            found = subs + links  # a class folder: each entry a team (one without: its verdict)
        else:
            try:
                find_package(path)
                found = [path]
            except SeveralPackages:
                found = subs + links
            except NoPackage:
                found = subs + links if len(paths) == 1 else [path]
        if found and found == links:
            raise UsageError(f"{raw}: {linked([shown(p.name) for p in links])}")
        if not found:
            raise UsageError(f"{raw}: no catkin package in it; give package folders")
        for folder in found:
            name = shown((folder if folder.is_symlink() else folder.resolve()).name)
            if name in out and out[name] != folder:
                name = f"{name}-{len(out)}"
            out[name] = folder
    return sorted(out.items())


def _one(team: str, folder: Path, rubric: Rubric, template: Template, options: Options
         ) -> tuple[PackageGrade, Submission | None]:  # fmt: skip
    if folder.is_symlink():  # a class folder's entry (teams() resolved the paths given)
        return refused(team, str(folder), linked([shown(folder.name)]), rubric), None
    try:
        sub = read_submission(folder, team)
    except UsarError as err:
        return refused(team, str(folder), str(err).removeprefix("--ros1 "), rubric), None
    with budget.spending(options.budget) as spend:
        got = grade(sub, rubric, template, options)
    if spend.spent:
        got = replace(got, findings=(spent_line(spend), *got.findings))
    return got, sub


def spent_line(spend: budget.Spend) -> str:
    """The verdict line of a team whose budget was spent (first of its findings)."""
    return f"budget spent: {spend.spent} (of {spend.budget.words()}); the lines say what it cut"


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

    pool = ThreadPoolExecutor(max(1, jobs))
    try:
        done = list(pool.map(lambda t: one(*t), found))
    except BaseException:  # a signal (Terminated) or a bug: end now, the tools with it
        tools.stop_all()
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    pool.shutdown()
    pairs: list[similarity.Pair] = []
    subs = [s for _, s in done if s is not None]
    if len(subs) > 1:
        bp = similarity.boilerplate(template.sources)
        prints = [similarity.prints(s.name, s.sources, bp) for s in subs]
        pairs = similarity.similar(prints, threshold)
    return ClassCode(tuple(g for g, _ in done), tuple(pairs), threshold)
