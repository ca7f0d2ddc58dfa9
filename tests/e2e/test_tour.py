"""The README's tour runs as written, in order, after the set-up command.

Why: the tour is the first thing a new user types; it went stale twice (a command refused
because the set-up had already written its output, a file that did not exist). This test reads
the tour's code block out of README.md and runs every command, in order, in a temporary folder,
as ``python -m usar_replay.cli`` with this checkout on ``PYTHONPATH``, and checks each exit code:
0, or the code the command's comment names (``(exit 1)``).

What it changes, and only this (the course world takes minutes to record): every
``usar record`` line records a small one-room world instead of its own (``--seed`` and
``--scenario`` are replaced by ``--scenario quick-room.toml``), and a line without ``--out``
gets ``--out`` set to the file it would have written (``recordings/course.mcap``,
``recordings/course-seed3.mcap``), so the later commands find what they expect. Every other
word of every command is the README's. The set-up's recording is stood in for by a file at
``recordings/course.mcap`` (only its existence matters: the tour's first command must replace
it). ``usar view`` runs with no ``DISPLAY``, so it writes ``recordings/course.rrd`` instead of
opening a window.

Every ``usar`` subcommand is in the tour, or in :data:`LEFT_OUT` with the reason; a new
subcommand (``usar echo``, ``usar log``) fails :func:`test_the_tour_shows_every_command` until
the tour shows it or says why not.
"""

from __future__ import annotations

import dataclasses
import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from example_worlds import quick_room

from usar_replay.cli.parser import build_parser
from usar_replay.world.scenario_toml import to_toml

ROOT = Path(__file__).resolve().parents[2]
README = ROOT / "README.md"
LEFT_OUT = {
    "batch": "it needs a folder of submissions; the section 'Grading a class' shows it",
    "recover": "it needs a killed recording; the tour shows it as a comment",
    "gradescope": (
        "it grades /autograder/submission inside Gradescope's container; "
        "tests/cli/commands/test_gradescope.py runs docs/gradescope.md's recipe as written"
    ),
}
"""Subcommands the tour does not run, and why."""


def tour() -> list[tuple[list[str], int, str]]:
    """The tour's commands: (words, expected exit code, the README's line)."""
    text = README.read_text(encoding="utf-8")
    block = text.split("## A tour", 1)[1].split("```sh\n", 1)[1].split("```", 1)[0]
    out = []
    for line in block.splitlines():
        parsed = parse_line(line)
        if parsed is not None:
            out.append((*parsed, line))
    return out


def parse_line(line: str) -> tuple[list[str], int] | None:
    """A tour line's words and expected exit code (``(exit N)`` in its comment, else 0); None
    for a blank or comment line."""
    if not line.strip() or line.lstrip().startswith("#"):
        return None
    command, _, comment = line.partition("  #")
    m = re.search(r"\(exit (\d+)", comment)
    return shlex.split(command), int(m.group(1)) if m else 0


def _subcommands() -> set[str]:
    import argparse

    for action in build_parser()._actions:
        if isinstance(action, argparse._SubParsersAction):
            return set(action.choices)
    raise AssertionError("no subcommands")


def test_the_tour_shows_every_command() -> None:
    shown = {words[1] for words, _, _ in tour()}
    missing = _subcommands() - shown - set(LEFT_OUT)
    assert not missing, f"the README's tour does not show: {sorted(missing)}"
    assert not set(LEFT_OUT) & shown, "a command in LEFT_OUT is in the tour now"


def _small_world(words: list[str], room: Path) -> list[str]:
    """A ``usar record`` line on the one-room world, writing where the line would have."""
    from usar_replay.cli import options
    from usar_replay.pipeline.record import default_output

    args = build_parser().parse_args(words[1:])
    out = [] if args.out else ["--out", str(default_output(options.load_scenario(args)))]
    kept: list[str] = []
    skip = False
    for w in words[2:]:
        if skip:
            skip = False
            continue
        if w in ("--seed", "--scenario"):
            skip = True
            continue
        kept.append(w)
    return ["record", *kept, "--scenario", str(room), *out]


def test_the_tour_runs_as_written(tmp_path: Path) -> None:
    commands = tour()
    assert len(commands) >= 10 and all(w[0] == "usar" for w, _, _ in commands)
    work = tmp_path / "clone"
    shutil.copytree(ROOT / "examples", work / "examples")
    (work / "recordings").mkdir()
    (work / "recordings" / "course.mcap").write_bytes(b"the set-up's recording")
    room = tmp_path / "quick-room.toml"
    # the minimal mission comes home after about 75 sim-seconds: a world whose time limit it
    # keeps, so that the tour's record ends as `done` (exit 0) within the TA's clock
    room.write_text(to_toml(dataclasses.replace(quick_room(), time_limit_s=90.0)), encoding="utf-8")
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")])
    for words, code, line in commands:
        args = _small_world(words, room) if words[1] == "record" else words[1:]
        res = subprocess.run(
            [sys.executable, "-m", "usar_replay.cli", *args],
            cwd=work,
            env=env,
            capture_output=True,
            text=True,
            check=False,
            stdin=subprocess.DEVNULL,
        )
        assert res.returncode == code, (
            f"{line}\nexit {res.returncode}, expected {code}\n{res.stdout[-2000:]}\n"
            f"{res.stderr[-2000:]}"
        )
        assert "Traceback" not in res.stderr, line
    # what the tour says it makes is there
    for made in ("runs/alice.mcap", "grades.xml", "grades.csv", "pages/index.html"):
        assert (work / made).is_file(), made
    assert (work / "recordings" / "course.rrd").is_file()


@pytest.mark.parametrize(
    ("line", "expected"),
    [
        (
            "usar record --overwrite   # x (the set-up made one)",
            (["usar", "record", "--overwrite"], 0),
        ),
        (
            "usar replay --mission f.py L  # costs (exit 1)",
            (["usar", "replay", "--mission", "f.py", "L"], 1),
        ),
        ("# usar recover x.part", None),
        ("   ", None),
    ],
)
def test_a_tour_line(line: str, expected: tuple[list[str], int] | None) -> None:
    """A command, its expected exit code from its comment; comments and blank lines skipped."""
    assert parse_line(line) == expected
