"""A run's limits as one value: what one run of a team's code may use, and its JSON/TOML form.

Why one dataclass: the limits of a run (wall seconds per tick, memory of the mission process
and of the run as a whole, processes, the run's folder, the ROS 1 bridge's budgets, the build's
folder and time, the grader's time) are set by the CLI, carried by a batch's plan to its
engines and across Ray as JSON, and read by the mission process, the ROS 1 bridge and the
build. Written out once per place they drifted apart (a default here, a check there); here each
field has its one default, its one range and its one command-line flag, and :data:`FLAGS` is the
table the CLI's options are made from (:mod:`usar_replay.cli.parser_parts`).

Why in core: most fields are not the sandbox's concern (a tick's timeout is the mission
process's, the holds are the ROS 1 bridge's, the grade's time is the batch's), and every layer
that runs a team's code reads them.

The JSON/TOML form (docs/batch.md, "A run's limits") is a flat table of these fields plus
``format = "usar-limits/1"``; a key usar does not know, a value of the wrong type or out of its
range is one line naming it. Wall-clock limits decide verdicts only: none reaches a logged byte.
"""

from __future__ import annotations

import dataclasses
import json
import math
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, NamedTuple

from usar_replay.core.errors import UsageError

__all__ = [
    "BATCH_LIMITS",
    "FLAGS",
    "GRADESCOPE_LIMITS",
    "LIMITS_FORMAT",
    "Flag",
    "RunLimits",
    "check_value",
    "limits_from_json",
    "limits_from_toml",
    "load_limits",
]

LIMITS_FORMAT = "usar-limits/1"
"""The JSON/TOML form's version: a reader refuses another (a renamed field is a new format)."""

_ALL = ("record", "replay", "batch", "gradescope")
_BATCHES = ("batch", "gradescope")


def _limit(
    default: float,
    *,
    flag: str = "",
    unit: str,
    lo: float,
    lo_open: bool = False,
    zero: str = "",
    help: str = "",
    commands: tuple[str, ...] = _ALL,
    metavar: str = "",
) -> Any:
    """A field with its range (``lo``, open when ``lo_open``), what 0 means (``zero``: "none",
    "no budget"), and its flag, help and commands (no ``flag``: set by code only)."""
    meta = {
        "flag": flag,
        "unit": unit,
        "lo": lo,
        "lo_open": lo_open,
        "zero": zero,
        "help": help,
        "commands": commands if flag else (),
        "metavar": metavar,
    }
    return field(default=default, metadata=meta)


@dataclass(frozen=True, slots=True, kw_only=True)
class RunLimits:
    """What one run may use. A value that exists is a valid one (checked however it was made:
    flags, a file, JSON from a batch's plan, Python)."""

    def __post_init__(self) -> None:
        for f in dataclasses.fields(RunLimits):
            check_value(f.name, getattr(self, f.name))

    tick_timeout_s: float = _limit(
        10.0, flag="--tick-timeout", unit="s", lo=0.0, lo_open=True,
        help="wall seconds a tick's callbacks may take before the mission is 'hung'",
    )  # fmt: skip
    startup_timeout_s: float = _limit(60.0, unit="s", lo=0.0, lo_open=True)
    """Wall seconds for importing the mission and running its ``main()``."""
    memory_mb: int = _limit(
        4096, flag="--mission-memory", unit="MiB", lo=0, zero="none",
        help="memory limit (address space) of the mission process in MiB",
    )  # fmt: skip
    cpu_s: int = _limit(
        0, flag="--cpu-limit", unit="s", lo=0, zero="none",
        help="CPU seconds of the mission process (and of each build process); past it 'hung'",
    )  # fmt: skip
    wall_s: float = _limit(
        3600.0, flag="--wall-limit", unit="s", lo=0.0, zero="none",
        help="wall seconds for the whole run, start-up included; past it 'wall_limit'",
    )  # fmt: skip
    max_log_mib: int = _limit(
        2048, flag="--max-log-mib", unit="MiB", lo=0, zero="none",
        help="byte budget of the run's log in MiB; past it the run is 'refused'",
    )  # fmt: skip
    run_memory_mb: int = _limit(
        3072, flag="--run-memory", unit="MiB", lo=0, zero="none",
        help="memory of the whole run, its tmpfs files included, MiB; past it 'out_of_memory'",
    )  # fmt: skip
    processes: int = _limit(
        256, flag="--processes", unit="", lo=1,
        help="processes and threads of the run; reaching it: 'refused'",
    )  # fmt: skip
    run_folder_mb: int = _limit(
        512, flag="--run-folder", unit="MiB", lo=0, zero="no limit",
        help="size of the run's writable folder, MiB; filling it: 'refused'",
    )  # fmt: skip
    max_holds: int = _limit(
        20, flag="--max-holds", unit="", lo=0, zero="no budget",
        help="ROS 1 ticks held for a node's shutdown; past it 'hung'",
    )  # fmt: skip
    hold_wall_s: float = _limit(
        30.0, flag="--hold-wall", unit="s", lo=0.0, zero="no budget",
        help="wall seconds the ROS 1 shutdown holds may take together; past it 'hung'",
    )  # fmt: skip
    max_capped: int = _limit(
        600, flag="--max-capped", unit="", lo=0, zero="no budget",
        help="ROS 1 ticks that reach their wall cap; past it 'hung'",
    )  # fmt: skip
    rtf: float = _limit(
        0.5, flag="--rtf", unit="", lo=0.0, zero="no cap", metavar="R",
        help="a ROS 1 package: the slowest pace; a tick waits at most dt/R of wall time for the "
        "graph to go idle, past it the tick is 'capped' (lower it on a slow or emulated machine)",
    )  # fmt: skip
    build_wall_s: float = _limit(
        900.0, flag="--build-timeout", unit="s", lo=0.0, lo_open=True,
        help="a ROS 1 package: wall seconds the catkin build may take",
    )  # fmt: skip
    connect_s: float = _limit(
        60.0, flag="--connect-timeout", unit="s", lo=0.0, lo_open=True,
        help="a ROS 1 package: wall seconds its graph has to start and register its nodes "
        "(raise it on a slow or emulated machine)",
    )  # fmt: skip
    build_folder_mb: int = _limit(
        2048, flag="--build-folder", unit="MiB", lo=0, zero="no limit",
        help="a ROS 1 package: its build's workspace while catkin runs, MiB, and 100,000 "
        "files; filling it: 'build_failed', nothing kept",
    )  # fmt: skip
    grade_s: float = _limit(
        600.0, flag="--grade-limit", unit="s", lo=0.0, lo_open=True, commands=_BATCHES,
        help="wall seconds to grade one log; past it the grade says 'grade_limit'",
    )  # fmt: skip
    cpus: int = _limit(0, unit="", lo=0, zero="two when free, else one")
    """CPUs of the run's own CPU set (a batch's engine gives each run its share)."""

    # -- the JSON/TOML form ----------------------------------------------------------------------

    def to_dict(self) -> dict[str, Any]:
        """The JSON/TOML form: ``format`` and every field, in class order."""
        return {"format": LIMITS_FORMAT, **self.values()}

    def values(self) -> dict[str, Any]:
        """Every field by name (what a subclass that adds context is built from)."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(RunLimits)}

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), sort_keys=True)

    def to_toml(self) -> str:
        """A ``[limits]`` table (what ``--limits FILE`` reads)."""
        import tomli_w  # deferred: reading limits never writes TOML

        return tomli_w.dumps({"limits": self.to_dict()})

    @classmethod
    def from_mapping(
        cls, data: Mapping[str, Any], source: str = "limits", base: RunLimits | None = None
    ) -> RunLimits:
        """Limits from their JSON/TOML form (``format`` may be left out of a hand-written
        file; another version is refused); missing fields keep ``base``'s (default: the
        defaults). Errors name ``source`` and the key."""
        fmt = data.get("format", LIMITS_FORMAT)
        if fmt != LIMITS_FORMAT:
            raise UsageError(f"{source}: format {fmt!r} is not {LIMITS_FORMAT!r}")
        names = {f.name for f in dataclasses.fields(RunLimits)}
        unknown = sorted(k for k in data if k not in names and k != "format")
        if unknown:
            raise UsageError(
                f"{source}: {unknown[0]}: not a limit (known: {', '.join(sorted(names))})"
            )
        values = {k: v for k, v in data.items() if k in names}
        for k, v in values.items():
            check_value(k, v, f"{source}: {k}")
        return RunLimits(**{**(base or RunLimits()).values(), **values})


class Flag(NamedTuple):
    """One row of the table the CLI's limit options are made from."""

    name: str
    """The :class:`RunLimits` field."""
    flag: str
    dest: str
    """The argparse attribute (``--tick-timeout`` -> ``tick_timeout``)."""
    kind: type
    metavar: str
    help: str
    zero: str
    commands: tuple[str, ...]


def _flags() -> tuple[Flag, ...]:
    hints = {"int": int, "float": float}
    rows = []
    for f in dataclasses.fields(RunLimits):
        meta = f.metadata
        if not meta["flag"]:
            continue
        kind = hints[str(f.type)]
        metavar = meta["metavar"] or {"MiB": "MIB", "s": "S"}.get(meta["unit"], "N")
        rows.append(
            Flag(
                f.name,
                meta["flag"],
                meta["flag"].removeprefix("--").replace("-", "_"),
                kind,
                metavar,
                meta["help"],
                meta["zero"],
                meta["commands"],
            )
        )
    return tuple(rows)


FLAGS = _flags()
"""Every limit a command line sets: ``--tick-timeout`` ... ``--grade-limit``."""

_FIELDS = {f.name: f for f in dataclasses.fields(RunLimits)}
_BY_NAME = {row.name: row for row in FLAGS}


def check_value(name: str, value: Any, label: str = "") -> None:
    """The one check of a limit's value (its type, finite, its range), as one line that says
    what is wrong and what 0 means: ``--processes 0: expected 1 or more``. ``label``: how the
    value was given (default: its flag, else the field's name)."""
    f = _FIELDS[name]
    meta = f.metadata
    row = _BY_NAME.get(name)
    label = label or (row.flag if row else name)
    unit = {"s": "seconds", "MiB": "MiB"}.get(meta["unit"], "")
    if meta["lo_open"]:
        want = f"a positive number of {unit or 'units'}"
    elif meta["lo"] >= 1:
        want = f"{meta['lo']:g} or more"
    else:
        want = f"{unit} >= 0 (0: {meta['zero']})" if unit else f"0 ({meta['zero']}) or more"
    integer = str(f.type) == "int"
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise UsageError(f"{label} {value!r}: expected {'a whole number' if integer else want}")
    if integer and not float(value).is_integer():
        raise UsageError(f"{label} {value!r}: expected a whole number, {want}")
    ok = math.isfinite(value) and (value > meta["lo"] if meta["lo_open"] else value >= meta["lo"])
    if not ok:
        raise UsageError(f"{label} {value}: expected {want}")


def limits_from_json(text: str, source: str = "limits") -> RunLimits:
    """:meth:`RunLimits.to_json`'s text back (a batch's run reads its job's limits so)."""
    try:
        data = json.loads(text)
    except ValueError as err:
        raise UsageError(f"{source}: not JSON: {err}") from None
    if not isinstance(data, dict):
        raise UsageError(f"{source}: expected a JSON object of limits")
    return RunLimits.from_mapping(data, source)


def limits_from_toml(text: str, source: str = "limits", base: RunLimits | None = None) -> RunLimits:
    """A ``[limits]`` table (or a file of only its keys) over ``base``."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise UsageError(f"{source}: invalid TOML: {err}") from None
    table = data.get("limits", data)
    if not isinstance(table, dict):
        raise UsageError(f"{source}: [limits] is not a table")
    return RunLimits.from_mapping(table, source, base)


def load_limits(path: str, base: RunLimits | None = None) -> RunLimits:
    """``--limits FILE``: its ``[limits]`` table over ``base``; a file usar cannot read is one
    line naming it."""
    try:
        with open(path, encoding="utf-8") as f:
            text = f.read(1 << 20)
    except FileNotFoundError:
        raise UsageError(f"--limits {path}: no such file") from None
    except (OSError, UnicodeDecodeError) as err:
        raise UsageError(f"--limits {path}: cannot read it ({err.__class__.__name__})") from None
    return limits_from_toml(text, f"--limits {path}", base)


BATCH_LIMITS = RunLimits(cpu_s=1800)
"""``usar batch``'s defaults: as ``usar record``'s, and 30 CPU minutes per mission process (a
class's runs share the machine; a spinning team is ``hung`` rather than everyone's wait)."""

GRADESCOPE_LIMITS = RunLimits(cpu_s=1800, run_memory_mb=512, wall_s=1500.0, build_folder_mb=1024)
"""``usar gradescope``'s defaults, for Gradescope's default container (768 MB of memory, half a
CPU; docs/gradescope.md): the run's memory below the container's, less its recorder (about
200 MiB) and usar; a run's wall time inside a 40-minute autograder timeout; a build folder that
fits a tmpfs counted against the same memory. Raise them with the container's size."""
