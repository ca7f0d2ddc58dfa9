"""What several commands read from their arguments: the world, the settings, the mission's
limits, the thresholds, the recordings named, and the grade outputs (checked before any work).

Why one module: ``record``, ``replay``, ``scenario`` and ``batch`` take the same world and
settings options and must read them the same way; each command module keeps only its own.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from usar_replay.core.errors import UsageError

if TYPE_CHECKING:
    from usar_replay.core.limits import RunLimits
    from usar_replay.core.settings import RunSettings, Thresholds
    from usar_replay.grading.verdict import GradeReport
    from usar_replay.process.mission_process import MissionLimits
    from usar_replay.world.scenario import Scenario
    from usar_replay.world.world_key import WorldKey

__all__ = [
    "add_world_key",
    "parse_camera",
    "world_key",
    "load_scenario",
    "given_settings",
    "overrides",
    "run_settings",
    "limits",
    "run_limits",
    "grader_paths",
    "OUTPUT_OPTIONS",
    "output_inputs",
    "check_outputs",
    "identity",
    "reports_out",
    "thresholds",
    "find_recordings",
]


def parse_camera(text: str) -> tuple[int, int, float]:
    """``640x480@10`` -> (640, 480, 10.0)."""
    import re

    m = re.fullmatch(r"(\d+)x(\d+)(?:@(\d+(?:\.\d+)?))?", text.strip())
    if not m:
        raise UsageError(f"--camera {text!r}: expected WIDTHxHEIGHT[@RATE], e.g. 640x480@10")
    w, h, rate = int(m.group(1)), int(m.group(2)), float(m.group(3) or 10)
    if not (16 <= w <= 4096 and 16 <= h <= 4096 and 0 < rate <= 60):
        raise UsageError(f"--camera {text!r}: size 16..4096 pixels and rate 0..60 Hz")
    return w, h, rate


def load_scenario(args: argparse.Namespace) -> Scenario:
    from usar_replay.world import assignment, scenario_toml

    kind = getattr(args, "assignment", None)
    if kind and kind not in assignment.names():
        known = ", ".join(assignment.names())
        raise UsageError(f"--assignment {kind}: no such assignment (known: {known})")
    base = (
        scenario_toml.load(args.scenario)
        if args.scenario
        else assignment.by_name(kind or "usar").world()
    )
    if kind and base.assignment != kind:
        raise UsageError(
            f"{args.scenario} is a {base.assignment!r} world, not {kind!r}; drop --assignment"
        )
    key = world_key(args)  # read (and taken out of the environment) even without --seed
    if args.seed is not None:
        base = assignment.of(base).variant(base, args.seed, key)
    if args.camera:
        w, h, rate = parse_camera(args.camera)
        base = dataclasses.replace(
            base, camera=dataclasses.replace(base.camera, width=w, height=h, rate_hz=rate)
        )
    if args.encoding:
        base = dataclasses.replace(
            base, camera=dataclasses.replace(base.camera, encoding=args.encoding)
        )
    return base


def add_world_options(p: argparse.ArgumentParser) -> None:
    """The options that name a world, as :func:`load_scenario` reads them (``record`` and
    ``scenario`` take the same ones): a file or the assignment's world, a seeded variant (with
    its key), and the camera's size, rate and encoding."""
    p.add_argument("--scenario", metavar="FILE", help="scenario TOML (default: the course world)")
    p.add_argument("--seed", type=int, help="a seeded variant: markers moved, targets recomputed")
    add_world_key(p)
    p.add_argument(
        "--assignment",
        metavar="NAME",
        help="the built-in world of this assignment: usar (default), ros2-final or one a package"
        " adds (docs/assignments.md); a scenario file names its own",
    )
    p.add_argument("--camera", metavar="WxH@HZ", help="camera size and rate, e.g. 640x480@10")
    p.add_argument("--encoding", choices=["png", "jpeg"], help="recorded frame encoding")


def add_world_key(p: argparse.ArgumentParser) -> None:
    """``--world-key FILE``: the secret that keeps ``--seed`` worlds hidden."""
    p.add_argument(
        "--world-key",
        metavar="FILE",
        help="secret key for hidden seeded worlds (default: $USAR_WORLD_KEY; docs/batch.md)",
    )


def world_key(args: argparse.Namespace) -> WorldKey | None:
    """``--world-key FILE``, else the key in ``$USAR_WORLD_KEY``; the variable is removed from
    this process's environment either way, so no mission process started later inherits it."""
    from usar_replay.world.world_key import ENV_VAR, key_from_env, load_key

    from_env = key_from_env()
    os.environ.pop(ENV_VAR, None)
    path = getattr(args, "world_key", None)
    return load_key(path) if path else from_env


def overrides(items: Sequence[str] | None) -> dict[str, str]:
    overrides: dict[str, str] = {}
    for item in items or []:
        k, eq, v = item.partition("=")
        if not eq or not k.strip():
            raise UsageError(
                f"--set {item!r}: expected NAME=VALUE, e.g. detector.dictionary=DICT_5X5_50"
            )
        overrides[k.strip()] = v.strip()
    return overrides


def given_settings(args: argparse.Namespace) -> tuple[str, ...]:
    """The dotted names of the settings the user gave explicitly (``--set``, bare names in
    ``mission``, and ``--settings FILE``'s tables), sorted: a ROS 1 run lets them win over the
    package's own files (move_base's goal tolerances)."""
    names = set()
    for key in overrides(getattr(args, "set", None)):
        names.add(key if "." in key else f"mission.{key}")
    if getattr(args, "settings", None):
        import tomllib

        given = tomllib.loads(Path(args.settings).read_text(encoding="utf-8"))
        for table, values in given.items():
            if isinstance(values, dict):
                names.update(f"{table}.{k}" for k in values)
    return tuple(sorted(names))


def run_settings(args: argparse.Namespace, base: RunSettings) -> RunSettings:
    """``--settings FILE`` then ``--set NAME=VALUE`` on top of ``base`` (one codec for all)."""
    from usar_replay.core import settings as settings_mod

    out = base
    if getattr(args, "settings", None):
        data = settings_mod.load(settings_mod.RunSettings, args.settings)
        # only the tables the file has replace the base's
        import tomllib

        given = tomllib.loads(Path(args.settings).read_text(encoding="utf-8"))
        out = dataclasses.replace(
            out, **{k: getattr(data, k) for k in ("record", "mission", "detector") if k in given}
        )
    return settings_mod.apply_overrides(out, overrides(args.set), default_group="mission")


def run_limits(args: argparse.Namespace) -> RunLimits:
    """The run's limits from the command line: the command's defaults, then ``--limits
    FILE``'s ``[limits]`` table, then each limit flag given (checked as
    :func:`usar_replay.core.limits.check_value` checks any: one line naming the flag)."""
    from usar_replay.core.limits import FLAGS, RunLimits, check_value, load_limits

    base = getattr(args, "limits_base", None) or RunLimits()
    if getattr(args, "limits_file", None):
        base = load_limits(args.limits_file, base)
    given = {}
    for row in FLAGS:
        value = getattr(args, row.dest, None)
        if value is not None:
            check_value(row.name, value)
            given[row.name] = value
    return RunLimits(**{**base.values(), **given})


def limits(args: argparse.Namespace) -> MissionLimits:
    """The mission's limits: :func:`run_limits`, with every file the grader passed in hidden
    from the mission."""
    from usar_replay.process.mission_process import MissionLimits

    return MissionLimits.of(run_limits(args), hidden=grader_paths(args))


def grader_paths(args: argparse.Namespace) -> tuple[str, ...]:
    """Every file the grader passed in (the world, its key, the settings, the thresholds, the
    output): the sandboxed mission never reads one, wherever it lies (usar_replay.sandbox.hide)."""
    names = (
        *("scenario", "world_key", "settings", "thresholds", "limits_file"),
        *("out", "json", "junit", "csv"),
    )
    return tuple(str(getattr(args, n)) for n in names if getattr(args, n, None))


OUTPUT_OPTIONS = (("--json", "json"), ("--junit", "junit"), ("--csv", "csv"))


def output_inputs(args: argparse.Namespace, inputs: Sequence[str]) -> list[str]:
    """The files a grade output may never replace: the recordings read (and a replayed one)."""
    return [*inputs, *([args.file] if getattr(args, "file", None) else [])]


def check_outputs(args: argparse.Namespace, inputs: Sequence[str]) -> None:
    """Refuse bad outputs before any work: an input, a directory, an existing file without
    ``--overwrite``, or one path given to two options."""
    from usar_replay.core.outfiles import check_output

    seen: dict[Path, str] = {}
    for opt, name in OUTPUT_OPTIONS:
        path = getattr(args, name, None)
        if not path:
            continue
        p = check_output(
            path, overwrite=args.overwrite, inputs=output_inputs(args, inputs), option=opt
        )
        key = p.resolve()
        if key in seen:
            raise UsageError(f"{opt} {p}: also given to {seen[key]}; choose another path")
        seen[key] = opt


def identity(p: Path) -> tuple[int, int] | None:
    try:
        st = p.stat()
    except OSError:
        return None
    return (st.st_ino, st.st_mtime_ns)


def reports_out(
    args: argparse.Namespace,
    reports: Sequence[GradeReport],
    errors: Sequence[tuple[str, str]] = (),
    inputs: Sequence[str] = (),
) -> None:
    """Write the machine-readable reports asked for, each atomically; a recording that could
    not be graded at all is in them too (``errors``: (path, message)), so a CI run never loses
    one silently."""
    from usar_replay.core.outfiles import write_text
    from usar_replay.grading import reports as rep

    for opt, path, fmt in (
        ("--json", args.json, rep.to_json),
        ("--junit", args.junit, rep.to_junit),
        ("--csv", args.csv, rep.to_csv),
    ):
        if path:
            write_text(
                path,
                fmt(reports, errors),
                overwrite=args.overwrite,
                inputs=output_inputs(args, inputs),
                option=opt,
            )


def thresholds(args: argparse.Namespace) -> Thresholds | None:
    from usar_replay.grading.grade import load_thresholds

    return load_thresholds(args.thresholds) if args.thresholds else None


def find_recordings(names: Sequence[str]) -> list[str]:
    """Files as given; a folder is searched with its sub-folders for ``*.mcap`` (sorted; hidden
    files and folders and unfinished ``.part`` files are skipped)."""
    files: list[str] = []
    for name in names:
        p = Path(name)
        if p.is_dir():
            found = sorted(
                str(f)
                for f in p.rglob("*.mcap")
                if f.is_file() and not any(s.startswith(".") for s in f.relative_to(p).parts)
            )
            if not found:
                raise UsageError(f"{p}: no .mcap files in this folder or its sub-folders")
            files += found
        else:
            files.append(name)
    return files
