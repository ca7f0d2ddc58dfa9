"""cli/parser_parts: a bad command line is one ``usar: error:`` line; argument types; the option
groups several commands share."""

from __future__ import annotations

import argparse

import pytest

from usar_replay.cli import options
from usar_replay.cli.exits import EXIT_USAGE
from usar_replay.cli.parser_parts import (
    UsageParser,
    address,
    grade_outputs,
    mission_options,
    port,
    positive_seconds,
)


def test_a_bad_command_line_is_one_line_and_exit_2(capsys: pytest.CaptureFixture[str]) -> None:
    p = UsageParser(prog="usar grade")
    p.add_argument("--port", type=port)
    with pytest.raises(SystemExit) as caught:
        p.parse_args(["--port", "70000"])
    assert caught.value.code == EXIT_USAGE
    err = capsys.readouterr().err
    assert err == (
        "usar: error: argument --port: 70000 is not a port number (1-65535); "
        "see `usar grade --help`\n"
    )


@pytest.mark.parametrize(
    ("fn", "good", "want"),
    [(positive_seconds, "0.5", 0.5), (port, "9876", 9876), (address, "::1", "::1")],
)
def test_types_take_good_values(fn: object, good: str, want: object) -> None:
    assert fn(good) == want  # type: ignore[operator]


@pytest.mark.parametrize(
    ("fn", "bad", "why"),
    [
        (positive_seconds, "soon", "is not a number of seconds"),
        (positive_seconds, "0", "expected seconds above 0"),
        (positive_seconds, "nan", "expected seconds above 0"),
        (positive_seconds, "-1", "expected seconds above 0"),
        (port, "http", "is not a port number"),
        (port, "0", "0 is not a port number"),
        (address, "localhost", "'localhost' is not an IP address"),
    ],
)
def test_types_refuse_bad_values(fn: object, bad: str, why: str) -> None:
    with pytest.raises(argparse.ArgumentTypeError, match=why):
        fn(bad)  # type: ignore[operator]


def test_the_mission_options_are_what_options_limits_reads() -> None:
    p = argparse.ArgumentParser()
    mission_options(p, replay=False)
    args = p.parse_args(["--set", "a=1", "--set", "b=2", "--mission-memory", "0"])
    assert args.set == ["a=1", "b=2"] and args.mission is None
    got = options.limits(args)
    assert (got.tick_timeout_s, got.memory_mb, got.max_log_mib) == (10.0, 0, 2048)
    assert "the one the log recorded" in _help(mission_options, replay=True)
    assert "(default: builtin)" in _help(mission_options, replay=False)


def test_the_grade_outputs() -> None:
    p = argparse.ArgumentParser()
    grade_outputs(p)
    args = p.parse_args(["--json", "g.json", "--overwrite"])
    assert (args.json, args.junit, args.csv, args.overwrite) == ("g.json", None, None, True)
    assert options.grader_paths(args) == ("g.json",)


def _help(add: object, **kw: object) -> str:
    p = argparse.ArgumentParser()
    add(p, **kw)  # type: ignore[operator]
    return " ".join(p.format_help().split())
