"""cli/parser: every command module has its sub-parser, in the order ``usar --help`` lists
them, and building the parser loads no back end (``usar --help`` stays cheap)."""

from __future__ import annotations

import pkgutil
import subprocess
import sys

import pytest

from usar_replay.cli import commands
from usar_replay.cli.parser import COMMANDS, build_parser


def test_every_command_module_is_a_command() -> None:
    modules = {m.name for m in pkgutil.iter_modules(commands.__path__)}
    assert {c.__name__.rsplit(".", 1)[-1] for c in COMMANDS} == modules
    sub = next(a for a in build_parser()._actions if a.dest == "command")
    assert list(sub.choices) == [c.__name__.rsplit(".", 1)[-1] for c in COMMANDS]  # type: ignore[arg-type]


def test_each_command_runs_its_modules_run() -> None:
    parser = build_parser()
    args = parser.parse_args(["info", "a.mcap", "--quick"])
    assert args.func is commands.info.run and args.files == ["a.mcap"] and args.quick
    args = parser.parse_args(["scenario", "--seed", "3"])
    assert args.func is commands.scenario.run and args.seed == 3


def test_a_command_is_required_and_the_version_is_printed(
    capsys: pytest.CaptureFixture[str],
) -> None:
    with pytest.raises(SystemExit) as caught:
        build_parser().parse_args([])
    assert caught.value.code == 2
    assert capsys.readouterr().err.startswith("usar: error: the following arguments are required")
    with pytest.raises(SystemExit) as caught:
        build_parser().parse_args(["--version"])
    assert caught.value.code == 0 and capsys.readouterr().out.startswith("usar-replay ")


def test_building_the_parser_loads_no_back_end() -> None:
    code = (
        "import sys\n"
        "from usar_replay.cli.parser import build_parser\n"
        "build_parser()\n"
        "print(sorted(m for m in ('pybullet', 'mcap', 'rerun', 'cv2') if m in sys.modules))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]"
