"""The README's command table says exactly what each subcommand's ``--help`` offers.

Why: the README is what a new user reads first; an option it leaves out is an option nobody
finds, and one it names that does not exist is an error on the first try.
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import pytest

from usar_replay.cli.parser import build_parser as _parser

README = Path(__file__).resolve().parents[2] / "README.md"


def _subparsers() -> dict[str, argparse.ArgumentParser]:
    parser = _parser()
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    raise AssertionError("no subcommands")


def _readme_rows() -> dict[str, str]:
    rows: dict[str, str] = {}
    for line in README.read_text(encoding="utf-8").splitlines():
        m = re.match(r"^\| `usar (\w+)([^`]*)` \|", line)
        if m:
            rows[m.group(1)] = m.group(2)
    return rows


def _option_groups(parser: argparse.ArgumentParser) -> list[tuple[str, ...]]:
    """Each option's spellings (``("-o", "--out")``), help left out."""
    return [
        tuple(action.option_strings)
        for action in parser._actions
        if action.option_strings and not isinstance(action, argparse._HelpAction)
    ]


def test_every_subcommand_has_a_row() -> None:
    assert set(_subparsers()) == set(_readme_rows())


@pytest.mark.parametrize("command", sorted(_subparsers()))
def test_the_row_lists_exactly_the_options(command: str) -> None:
    row = _readme_rows()[command]
    documented = set(re.findall(r"(?<![\w-])--?[a-z][a-z0-9-]*", row))
    groups = _option_groups(_subparsers()[command])
    missing = [g for g in groups if not documented & set(g)]
    assert not missing, f"usar {command}: the README leaves out {missing}"
    known = {o for g in groups for o in g}
    assert documented <= known, f"usar {command}: the README names {documented - known}"
