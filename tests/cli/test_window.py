"""cli/window: --since/--until as sim seconds, the damaged-log note, and a reader gone away."""

from __future__ import annotations

import argparse
import sys

import pytest

from usar_replay.cli.exits import EXIT_INCOMPLETE, EXIT_OK
from usar_replay.cli.window import add_window, finish, window_ns, write_lines
from usar_replay.core.errors import UsageError


def _parse(*argv: str) -> argparse.Namespace:
    p = argparse.ArgumentParser(exit_on_error=False)
    add_window(p)
    return p.parse_args(argv)


def test_the_window_is_in_log_nanoseconds() -> None:
    assert window_ns(_parse()) == (None, None)
    assert window_ns(_parse("--since", "1.5", "--until", "12.3")) == (1_500_000_000, 12_300_000_000)
    assert window_ns(_parse("--since", "2", "--until", "2")) == (2_000_000_000, 2_000_000_000)


def test_an_empty_window_is_a_usage_error() -> None:
    with pytest.raises(UsageError, match=r"--until 1\.0 is before --since 2\.0"):
        window_ns(_parse("--since", "2", "--until", "1"))


@pytest.mark.parametrize(
    ("value", "why"),
    [("abc", "is not a number of seconds"), ("-1", "0 or more"), ("nan", "0 or more")],
)
def test_a_bad_time_is_refused_by_the_parser(value: str, why: str) -> None:
    with pytest.raises(argparse.ArgumentError, match=why):
        _parse("--since", value)


def test_finish_is_ok_or_one_note(capsys: pytest.CaptureFixture[str]) -> None:
    assert finish("", "a.mcap", "echoed") == EXIT_OK
    assert capsys.readouterr().err == ""
    assert finish("truncated", "a.mcap", "echoed") == EXIT_INCOMPLETE
    err = capsys.readouterr().err
    assert err == "usar: a.mcap: the log is incomplete (truncated); echoed as far as it goes\n"


def test_write_lines_counts_what_it_wrote(capsys: pytest.CaptureFixture[str]) -> None:
    assert write_lines(iter(["a", "b", "c"])) == 3
    assert capsys.readouterr().out == "a\nb\nc\n"
    assert sys.stdout is not None
