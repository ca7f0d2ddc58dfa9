"""The instructor's starts file: ``usar batch --starts starts.toml`` (issue 50).

Why: a team folder is the team's submission, so nothing in it (its ``usar.toml`` included) can
speak as the instructor: a team could otherwise give itself the TA's third command (any shell
text) or pass off its own choice as the grader's. What the instructor decides per team lives in
a file of the instructor's, named on the command line, one table per team::

    [group7]
    node = "final_project_node"
    after_launch = ['rosservice call /start "data: true"']
    note = "README names the wrong node; agreed in office hours"

``launch`` and ``node`` replace the team's start (the team's third commands too, unless
``after_launch`` is given); ``after_launch`` alone replaces only the third commands; ``note``
is shown with the start. A third command is a ``rosservice call`` or a ``rostopic pub``, one
command, never shell text (:func:`.start_prose.third_command`). A mistake in the file is a
usage error before anything runs.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from usar_replay.core.errors import UsageError
from usar_replay.core.safe_text import safe_line
from usar_replay.ros1.start_prose import third_command

__all__ = ["InstructorStart", "read_starts"]

_KEYS = frozenset({"launch", "node", "after_launch", "note"})
MAX_BYTES = 4 * 1024 * 1024


@dataclass(frozen=True, slots=True)
class InstructorStart:
    """One team's table of the instructor's starts file."""

    launch: str = ""
    node: str = ""
    after_launch: tuple[str, ...] | None = None
    """The third commands; None: the team's own (as its text says)."""
    note: str = ""
    label: str = ""
    """Where it was read, for people: ``the instructor's starts.toml [group7]``."""

    @property
    def source(self) -> str:
        """The label, with the instructor's note."""
        return self.label + (f": {safe_line(self.note)}" if self.note else "")

    def to_json(self) -> dict[str, Any]:
        """Plain data (it crosses to a batch's run as JSON)."""
        return {
            "launch": self.launch,
            "node": self.node,
            "after_launch": None if self.after_launch is None else list(self.after_launch),
            "note": self.note,
            "label": self.label,
        }

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> InstructorStart:
        after = data.get("after_launch")
        return cls(
            str(data.get("launch", "")),
            str(data.get("node", "")),
            None if after is None else tuple(str(a) for a in after),
            str(data.get("note", "")),
            str(data.get("label", "")),
        )


def read_starts(path: str | Path) -> dict[str, InstructorStart]:
    """The instructor's starts file, by team name; :class:`UsageError` (one line) for a file
    that is missing, not TOML, or not tables of ``launch``/``node``/``after_launch``/``note``."""
    file = Path(path)
    where = f"--starts {file}"
    try:
        with file.open("rb") as f:
            raw = f.read(MAX_BYTES + 1)
    except OSError as err:
        why = err.strerror or err
        raise UsageError(f"{where}: {why}; give the instructor's TOML file") from None
    if len(raw) > MAX_BYTES:
        raise UsageError(f"{where}: larger than {MAX_BYTES // 1024 // 1024} MiB")
    try:
        data = tomllib.loads(raw.decode("utf-8"))
    except (UnicodeDecodeError, tomllib.TOMLDecodeError, RecursionError) as err:
        raise UsageError(f"{where}: not valid TOML: {safe_line(str(err))}") from None
    out: dict[str, InstructorStart] = {}
    for team, table in data.items():
        at = f"{where} [{safe_line(team)}]"
        if not isinstance(table, dict):
            raise UsageError(f'{at}: expected a table per team ([TEAM] node = "EXE")')
        unknown = sorted(set(table) - _KEYS)
        if unknown:
            raise UsageError(f"{at}: unknown key {safe_line(unknown[0])!r} (launch, node, "
                             "after_launch, note)")  # fmt: skip
        values = [table.get(k, "") for k in ("launch", "node", "note")]
        if not all(isinstance(v, str) for v in values):
            raise UsageError(f'{at}: launch, node and note are strings ("go.launch")')
        launch, node, note = (str(v) for v in values)
        out[team] = InstructorStart(
            Path(launch).name,
            node,
            _third_commands(at, table.get("after_launch")),
            note,
            f"the instructor's {file.name} [{safe_line(team)}]",
        )
    return out


def _third_commands(at: str, value: object) -> tuple[str, ...] | None:
    if value is None:
        return None
    items = [value] if isinstance(value, str) else value
    if not isinstance(items, list) or not all(isinstance(a, str) for a in items):
        raise UsageError(f"{at}: after_launch is a list of commands")
    out: list[str] = []
    for item in items:
        command = third_command(item)
        if command is None:
            raise UsageError(
                f"{at}: after_launch {safe_line(item)!r} is not a rosservice call or a "
                "rostopic pub (the only third commands usar runs)"
            )
        out.append(command)
    return tuple(out)
