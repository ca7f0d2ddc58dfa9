"""`usar batch`: grade a class, every team's mission on every world, resumably.

Why this shape: a class is 30-100 teams and a fair grade uses several worlds per team; that is
hours of CPU, cut off now and then (a laptop lid, Ctrl-C, a cluster node lost). So the batch is
a plan of independent runs, each one (team, world) pair that writes only its own files, and a
finished run is recognised from its files alone:

``OUT/<team>/<world>.mcap``
    the log (``usar record``'s, through the same code);
``OUT/<team>/<world>.run.json``
    the run's manifest entry, written last: the inputs' digests (the team's code, the world, the
    settings and limits, the usar version), the log's size and sha256, the outcome;
``OUT/<team>/<world>.grade.json``
    the grade (format ``usar-batch-grade/1``, docs/batch.md), tied to the log by its sha256;
``OUT/<team>/<world>.output.txt``
    what the mission printed (and the recorder's own messages).

A run whose manifest entry matches the current inputs and whose log has the recorded size is
finished and is not run again; one whose grade is missing or stale is only graded again; any
other is recorded from scratch (a log left by a run cut off is replaced). Every file is written
under a temporary name and renamed (:mod:`usar_replay.core.outfiles`), so a cut never leaves a file
that looks finished.

The runs themselves are executed by an engine (:mod:`usar_replay.batch.engines`: a local pool or
Ray), each in its own process (:mod:`usar_replay.batch.run_one`).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import re
import stat
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from usar_replay import __version__
from usar_replay.batch.team_files import UnusableSubmission, submission_digest
from usar_replay.core import team_parse
from usar_replay.core.errors import UnclearStart, UsageError
from usar_replay.core.folder_walk import linked, shown
from usar_replay.core.limits import BATCH_LIMITS, RunLimits
from usar_replay.ros1 import start
from usar_replay.ros1.building.workspace import NoPackage, SeveralPackages, find_package
from usar_replay.ros1.starts_file import InstructorStart
from usar_replay.world.world_key import WorldKey

__all__ = [
    "GRADE_FORMAT",
    "RUN_FORMAT",
    "Plan",
    "RunJob",
    "RunResult",
    "Submission",
    "World",
    "discover",
    "discover_team",
    "make_plan",
    "parse_seeds",
    "submission_digest",
]

RUN_FORMAT = "usar-batch-run/1"
GRADE_FORMAT = "usar-batch-grade/1"
CONFIG_FILE = "usar.toml"
ROS1_TARGET_PREFIX = "ros1:"
"""A team folder holding a catkin package: its target is ``ros1:<folder>`` (docs/ros1.md)."""
DEFAULT_MISSION_FILE = "mission.py"
WORK_DIR = ".work"
_NAME = re.compile(r"[^A-Za-z0-9._-]+")


@dataclass(frozen=True, slots=True)
class Submission:
    """One team: a sub-folder or a ``.py`` file of the submissions folder."""

    team: str
    path: Path
    """The folder (or the single file) the team handed in: its files are the team's own."""
    target: str
    """The mission target for ``usar record --mission`` (an absolute ``.py`` path, maybe with
    ``:function``); empty when the submission has none (:attr:`problem` says why)."""
    sha256: str
    """Digest of every file of the submission (sorted relative paths and bytes)."""
    problem: str = ""
    problem_outcome: str = "no_mission"
    """The verdict of every run of a submission with a :attr:`problem`: ``no_mission``, or
    ``bad_submission`` for a folder usar will not read (:mod:`usar_replay.batch.team_files`)."""
    start: str = ""
    """A ROS 1 team's start as a TA types it (``roslaunch P F; rosrun P N``); '' otherwise."""
    start_source: str = ""
    """Where :attr:`start` was read (``doc/instructions.txt line 7``, ``the team's usar.toml
    [ros1]``, ``the instructor's starts.toml [group7]``)."""
    instructor_start: dict[str, Any] = field(default_factory=dict)
    """The team's table of the instructor's starts file (``usar batch --starts``), as JSON."""


@dataclass(frozen=True, slots=True)
class World:
    """One world every team is graded on: a seeded variant or a scenario file."""

    name: str
    """``seed3``, or the scenario file's stem: the run's file names."""
    scenario_toml: str
    """The scenario as TOML (what the run loads; its digest is the world's identity)."""
    source: str
    """Where it came from, for people (``course world, seed 3``, a file path)."""

    @property
    def sha256(self) -> str:
        return hashlib.sha256(self.scenario_toml.encode()).hexdigest()


@dataclass(frozen=True, slots=True)
class RunJob:
    """One (team, world) run, as plain data: it crosses a process boundary and Ray as JSON."""

    team: str
    world: str
    target: str
    submission_path: str
    scenario_toml: str
    settings_toml: str
    thresholds_toml: str
    limits: dict[str, Any]
    """The run's limits in their JSON form (:meth:`RunLimits.to_dict`): :attr:`run_limits`."""
    team_dir: str
    out_root: str
    submissions_root: str
    inputs: dict[str, str]
    grade_only: bool = False
    start: str = ""
    """A ROS 1 team's start as the plan read it (:attr:`Submission.start`), for its grade."""
    start_source: str = ""
    sandbox: bool = True
    """Run the mission in the kernel sandbox (:mod:`usar_replay.sandbox.kernel_sandbox`) with
    the audit guard on; ``usar batch --no-sandbox`` turns both off."""

    @property
    def run_limits(self) -> RunLimits:
        """The run's limits (checked again: the job may have crossed Ray as JSON)."""
        return RunLimits.from_mapping(self.limits, f"the limits of {self.team} on {self.world}")

    def with_cpus(self, cpus: int) -> RunJob:
        """This job with its run's CPU set of ``cpus`` CPUs (an engine's share per run)."""
        limits = dataclasses.replace(self.run_limits, cpus=cpus)
        return dataclasses.replace(self, limits=limits.to_dict())

    instructor_start: dict[str, Any] = field(default_factory=dict)
    """The instructor's start for the team (:attr:`Submission.instructor_start`)."""

    @property
    def inputs_key(self) -> str:
        return _key(self.inputs)

    @property
    def thresholds_sha256(self) -> str:
        return hashlib.sha256(self.thresholds_toml.encode()).hexdigest()

    def path(self, suffix: str) -> Path:
        """``<team_dir>/<world><suffix>`` (``.mcap``, ``.run.json``, ``.grade.json``, ...)."""
        return Path(self.team_dir) / f"{self.world}{suffix}"

    @property
    def work_dir(self) -> Path:
        return Path(self.team_dir) / WORK_DIR / self.world

    def to_json(self) -> str:
        return json.dumps(asdict(self), sort_keys=True)

    @classmethod
    def from_json(cls, text: str) -> RunJob:
        return cls(**json.loads(text))


@dataclass(frozen=True, slots=True)
class RunResult:
    """What an engine hands back for one run (plain data)."""

    team: str
    world: str
    state: str
    """``graded`` (recorded or re-graded now), ``finished`` (done before, skipped), ``error``
    (usar could not record or grade it: it is redone next time), ``interrupted``."""
    outcome: str = ""
    points: float = 0.0
    max_points: float = 0.0
    wall_s: float = 0.0
    error: str = ""

    @property
    def failed(self) -> bool:
        """Did the team's code fail here (not done) or usar (error)?"""
        return self.state == "error" or self.outcome not in ("done", "")

    @classmethod
    def from_files(
        cls, team: str, world: str, state: str, grade: dict[str, Any], record: dict[str, Any]
    ) -> RunResult:
        """The result of a run whose ``.grade.json`` and ``.run.json`` are written: the planner
        (a run finished before) and the engines (a run just graded) read them the same way, so a
        skipped run and a fresh one report the same numbers."""
        return cls(
            team,
            world,
            state,
            str(grade.get("outcome", "")),
            float(grade.get("points", 0.0)),
            float(grade.get("max_points", 0.0)),
            float(record.get("wall_s", 0.0)),
        )


@dataclass(slots=True)
class Plan:
    """Every run of a batch and what each needs: record, grade only, or nothing."""

    out_root: Path
    submissions: list[Submission]
    worlds: list[World]
    jobs: list[RunJob] = field(default_factory=list)
    """The runs to execute (recording or grading only)."""
    finished: list[RunResult] = field(default_factory=list)
    """Runs finished before, with their grades."""
    invalid: list[RunResult] = field(default_factory=list)
    """Runs of submissions without a mission (0 points, nothing to run)."""

    @property
    def total(self) -> int:
        return len(self.submissions) * len(self.worlds)


def _key(data: dict[str, str]) -> str:
    return hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest()


def team_name(raw: str) -> str:
    """A file-name-safe team name (letters, digits, ``. _ -``)."""
    name = _NAME.sub("_", raw).strip("._") or "team"
    return name


def _folder_target(
    folder: Path, instructor: InstructorStart | None = None
) -> tuple[str, str, str, str]:
    """(target, problem, start, start source) of a team folder: ``usar.toml``'s ``[mission]
    target``, ``mission.py``, or a catkin package started as :func:`usar_replay.ros1.start.decide`
    reads it (``usar.toml [ros1]``, the instructions, the README, the package's shape)."""
    config = folder / CONFIG_FILE
    data: Any = {}
    if config.is_file():
        try:  # the team's file: bounded, depth-checked, one line (core/team_parse)
            data = team_parse.toml_file(config, CONFIG_FILE)
        except UnusableSubmission as err:
            return "", str(err), "", ""
    if config.is_file() and ("mission" in data or "ros1" not in data):  # a Python mission
        mission_table = data.get("mission", {})
        spec = mission_table.get("target") if isinstance(mission_table, dict) else None
        if not isinstance(spec, str) or not spec.strip():
            return "", f'{CONFIG_FILE} has no [mission] target = "FILE.py[:function]"', "", ""
        file_part, colon, func = spec.strip().partition(":")
        file = (folder / file_part).resolve()
        if not file.is_relative_to(folder.resolve()):
            return "", f"{CONFIG_FILE}: target {spec!r} is outside the team's folder", "", ""
        if file.suffix != ".py" or not file.is_file():
            why = f"{CONFIG_FILE}: target {spec!r}: no such .py file in the team's folder"
            return "", why, "", ""
        return str(file) + (f":{func}" if colon and func else ""), "", "", ""
    mission = folder / DEFAULT_MISSION_FILE
    if mission.is_file():
        return str(mission.resolve()), "", "", ""
    target = ROS1_TARGET_PREFIX + str(folder.resolve())
    try:  # every file catkin, roslaunch or usar parses, bounded before any of them reads it
        team_parse.check_package(folder)
    except UnusableSubmission as err:
        return "", str(err), "", ""
    try:  # a catkin package (the course's deliverable), found as `--ros1 FOLDER` finds it
        pkg = find_package(folder)
    except NoPackage:
        pass
    except SeveralPackages as err:  # which, and how to choose
        return "", str(err).removeprefix("--ros1 "), "", ""
    except UnusableSubmission as err:  # a package.xml past its cap (core/team_parse)
        return "", str(err), "", ""
    except UsageError:  # a package usar will say more about when it runs (no <name>...)
        return target, "", "", ""
    else:  # built and run by usar's ROS 1 bridge, started as the team's text says
        try:
            chosen = start.decide(pkg.path, pkg.name, team_dir=folder, instructor=instructor)
        except UnclearStart as err:
            return "", str(err), "", ""
        return target, "", "; ".join(chosen.commands(pkg.name)), chosen.source
    return (
        "",
        f"no {DEFAULT_MISSION_FILE}, no {CONFIG_FILE} and no package.xml in the team's folder",
        "",
        "",
    )


def discover(
    submissions_dir: str | os.PathLike[str],
    starts: Mapping[str, InstructorStart] | None = None,
) -> list[Submission]:
    """The teams of a submissions folder, sorted by name: each ``.py`` file and each sub-folder
    (its ``mission.py``, or the ``[mission] target`` of its ``usar.toml``). Names starting with
    ``.`` or ``_`` are skipped; a folder without a mission is a team with a :attr:`problem`, and
    so is an entry that is a link (``bad_submission``: never read through, as ``usar code``
    refuses it). ``starts``: the instructor's starts file by team (folder or team name;
    :mod:`usar_replay.ros1.starts_file`); a name of it that is no team is a usage error."""
    root = Path(submissions_dir)
    starts = starts or {}
    if not root.is_dir():
        raise UsageError(f"{root}: not a directory; give the folder of submissions")
    subs: list[Submission] = []
    seen: dict[str, str] = {}
    for entry in sorted(root.iterdir(), key=lambda p: p.name):
        if entry.name.startswith((".", "_")):
            continue
        if entry.is_file() and entry.suffix == ".py":
            raw, target, problem = entry.stem, str(entry.resolve()), ""
        elif entry.is_dir():
            raw, target, problem = entry.name, "", ""
        else:
            continue
        team = team_name(raw)
        told = starts.get(entry.name) or starts.get(team)
        if team in seen:
            raise UsageError(
                f"{root}: {seen[team]!r} and {entry.name!r} are both team {team!r}; rename one"
            )
        seen[team] = entry.name
        subs.append(_submission(team, entry, root, target, problem, told))
    if not subs:
        raise UsageError(f"{root}: no submissions (a .py file or a folder per team)")
    unknown = sorted(set(starts) - {s.team for s in subs} - set(seen.values()))
    if unknown:
        raise UsageError(
            f"--starts: [{shown(unknown[0])}] is no team of {root}; its teams are folder names "
            f"({', '.join(shown(s.team) for s in subs[:5])}{', ...' if len(subs) > 5 else ''})"
        )
    return subs


def _submission(
    team: str,
    entry: Path,
    root: Path,
    target: str,
    problem: str,
    told: InstructorStart | None = None,
) -> Submission:
    """One team's :class:`Submission`: a link is never read through, a folder's files are
    checked before anything else of it is read, then its target is found (as the instructor's
    ``told`` start says, where there is one)."""
    outcome = "no_mission"
    how = source = ""
    path = entry.resolve()
    if entry.is_symlink():  # never read through: it could lead anywhere (usar code agrees)
        path = root.resolve() / entry.name
        problem = f"unusable submission: {linked([shown(entry.name)])}"
        target, digest, outcome = "", "", "bad_submission"
    else:
        try:  # first: nothing else of a folder is read before it is known to be safe to read
            digest = submission_digest(path)
        except (UnusableSubmission, OSError) as err:
            reason = err if isinstance(err, UnusableSubmission) else err.strerror or err
            target, problem, digest = "", f"unusable submission: {reason}", ""
            outcome = "bad_submission"
        else:
            if entry.is_dir():
                target, problem, how, source = _folder_target(entry, told)
    told_json = told.to_json() if told is not None else {}
    return Submission(team, path, target, digest, problem, outcome, how, source, told_json)


def discover_team(folder: str | os.PathLike[str], team: str = "submission") -> Submission:
    """One team folder graded in place, as :func:`discover` reads each of a class's (Gradescope's
    ``/autograder/submission``: no class folder around it, no link, no copy)."""
    path = Path(folder)
    if not path.is_dir() or path.is_symlink():
        raise UsageError(f"{path}: not a folder; give the team's submission folder")
    return _submission(team_name(team), path, path.parent, "", "")


def parse_seeds(text: str) -> list[int]:
    """``0-4`` -> [0, 1, 2, 3, 4]; ``0,3,7-8`` -> [0, 3, 7, 8] (sorted, no repeats)."""
    seeds: set[int] = set()
    for part in text.split(","):
        part = part.strip()
        m = re.fullmatch(r"(\d+)(?:-(\d+))?", part)
        if not m:
            raise UsageError(f"--seeds {text!r}: expected N, N-M or a comma list, e.g. 0-4")
        lo, hi = int(m.group(1)), int(m.group(2) or m.group(1))
        if hi < lo or hi - lo > 10_000:
            raise UsageError(f"--seeds {text!r}: {part} is not a range from low to high")
        seeds.update(range(lo, hi + 1))
    return sorted(seeds)


def make_worlds(
    seeds: Sequence[int], scenario_files: Sequence[str], world_key: WorldKey | None = None
) -> list[World]:
    """The worlds: each seed as a variant of the course world (keyed by ``world_key`` when
    given: hidden worlds, :mod:`usar_replay.world.world_key`), then each scenario file (the
    course world alone when neither is given)."""
    from usar_replay.world.scenario import course_world
    from usar_replay.world.scenario_toml import load, to_toml

    worlds: list[World] = []
    if seeds:
        from usar_replay.world.variants import make_variant

        base = course_world()
        keyed = "" if world_key is None else ", keyed"
        for s in seeds:
            variant = to_toml(make_variant(base, s, world_key))
            worlds.append(World(f"seed{s}", variant, f"course, seed {s}{keyed}"))
    for f in scenario_files:
        worlds.append(World(team_name(Path(f).stem), to_toml(load(f)), str(f)))
    if not worlds:
        worlds.append(World("course", to_toml(course_world()), "the course world"))
    names = [w.name for w in worlds]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise UsageError(f"two worlds are named {dup[0]!r}; give the scenario files other names")
    return worlds


def read_json(path: Path) -> dict[str, Any] | None:
    """A JSON object, or None for a file that is missing or not one (a cut write cannot be
    one: writes are atomic; a hand-edited file can). Never read through a link: usar writes
    its grades and records as plain files, so a link there is not one of them."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC)
        with os.fdopen(fd, "rb") as f:
            if not stat.S_ISREG(os.fstat(f.fileno()).st_mode):
                return None
            data = json.loads(f.read(64 * 1024 * 1024).decode("utf-8"))
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


def finished_record(job: RunJob) -> dict[str, Any] | None:
    """The run's manifest entry when the run is finished for these inputs (else None)."""
    rec = read_json(job.path(".run.json"))
    if rec is None or rec.get("format") != RUN_FORMAT or rec.get("inputs_key") != job.inputs_key:
        return None
    log = job.path(".mcap")
    try:
        if log.stat().st_size != rec.get("log_bytes"):
            return None
    except OSError:
        return None
    return rec


def current_grade(job: RunJob, record: dict[str, Any]) -> dict[str, Any] | None:
    """The run's grade when it grades this very log with these thresholds (else None)."""
    grade = read_json(job.path(".grade.json"))
    if (
        grade is None
        or grade.get("format") != GRADE_FORMAT
        or grade.get("log_sha256") != record.get("log_sha256")
        or grade.get("thresholds_sha256") != job.thresholds_sha256
    ):
        return None
    return grade


def make_plan(
    submissions: Sequence[Submission],
    worlds: Sequence[World],
    out_root: str | os.PathLike[str],
    *,
    settings_toml: str,
    thresholds_toml: str = "",
    limits: RunLimits | None = None,
    sandbox: bool = True,
    submissions_root: str | os.PathLike[str],
) -> Plan:
    """Every (team, world) run and what it needs, judged from the files already in ``out_root``
    (``limits``: default :data:`~usar_replay.core.limits.BATCH_LIMITS`)."""
    limits_dict = (limits or BATCH_LIMITS).to_dict()
    out = Path(out_root).resolve()
    plan = Plan(out, list(submissions), list(worlds))
    run_inputs = {**limits_dict, "sandbox": sandbox}  # another limit is another run
    settings_sha = hashlib.sha256(
        (settings_toml + json.dumps(run_inputs, sort_keys=True)).encode()
    ).hexdigest()
    for sub in submissions:
        for world in worlds:
            job = RunJob(
                team=sub.team,
                world=world.name,
                target=sub.target,
                submission_path=str(sub.path),
                scenario_toml=world.scenario_toml,
                settings_toml=settings_toml,
                thresholds_toml=thresholds_toml,
                limits=limits_dict,
                team_dir=str(out / sub.team),
                out_root=str(out),
                submissions_root=str(Path(submissions_root).resolve()),
                inputs=_inputs(sub, world, settings_sha),
                start=sub.start,
                start_source=sub.start_source,
                sandbox=sandbox,
                instructor_start=sub.instructor_start,
            )
            if sub.problem:
                plan.invalid.append(
                    RunResult(
                        sub.team, world.name, "graded", sub.problem_outcome, error=sub.problem
                    )
                )
                continue
            record = finished_record(job)
            if record is None:
                plan.jobs.append(job)
                continue
            grade = current_grade(job, record)
            if grade is None:
                plan.jobs.append(RunJob(**{**asdict(job), "grade_only": True}))
                continue
            plan.finished.append(
                RunResult.from_files(sub.team, world.name, "finished", grade, record)
            )
    return plan


def _inputs(sub: Submission, world: World, settings_sha: str) -> dict[str, str]:
    """What a finished run was made of: a run is redone when one of these changes."""
    inputs = {
        "mission_sha256": sub.sha256,
        "mission_target": _relative_target(sub),
        "scenario_sha256": world.sha256,
        "settings_sha256": settings_sha,
        "usar_version": __version__,
    }
    if sub.instructor_start:  # only then: a class graded without one keeps its runs
        inputs["instructor_start"] = _key(sub.instructor_start)
    return inputs


def _relative_target(sub: Submission) -> str:
    """The target relative to the submission (a moved submissions folder is the same input)."""
    if not sub.target:
        return ""
    if sub.target.startswith(ROS1_TARGET_PREFIX):
        return ROS1_TARGET_PREFIX + "."  # the team's folder is the package
    file_part, colon, func = sub.target.partition(":")
    base = sub.path.parent if sub.path.is_file() else sub.path
    rel = Path(file_part).relative_to(base).as_posix()
    return rel + (f":{func}" if colon else "")
