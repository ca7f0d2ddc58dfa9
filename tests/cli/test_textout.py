"""cli/textout: lines for people fit 100 columns."""

from __future__ import annotations

import io

from usar_replay.cli.textout import WIDTH, incomplete_note, print_wrapped, wrap


def test_wrap_keeps_lines_within_the_width_and_indents_continuations() -> None:
    text = "usar: " + " ".join(["word"] * 60)
    lines = wrap(text)
    assert len(lines) > 1
    assert all(len(line) <= WIDTH for line in lines)
    assert all(line.startswith("  word") for line in lines[1:])
    assert " ".join(line.strip() for line in lines) == text


def test_a_hyphenated_path_is_not_broken_but_an_overlong_one_is() -> None:
    path = "/home/team-a/run-2026-11-24/log.mcap"
    assert wrap(f"saved to {path}", width=40) == ["saved to", f"  {path}"]
    long = "x" * 250
    assert [len(line) for line in wrap(long)] == [100, 100, 54]
    assert wrap("") == [""]


def test_print_wrapped_writes_to_the_given_file() -> None:
    out = io.StringIO()
    print_wrapped("a " * 80, file=out, width=40)
    lines = out.getvalue().splitlines()
    assert len(lines) == 5 and all(len(line) <= 40 for line in lines)
    assert " ".join(lines).split() == ["a"] * 80


def test_incomplete_note_is_one_line_shortened_to_fit() -> None:
    short = incomplete_note("a.mcap", "truncated", "graded")
    assert short == "usar: a.mcap: the log is incomplete (truncated); graded as far as it goes"
    problem = (
        "the file ends inside a chunk at byte 123456789 (the recorder was killed); "
        "read 4211 messages up to sim time 96.250 s"
    )
    note = incomplete_note("runs/team-a.mcap", problem, "graded")
    assert note == (
        "usar: runs/team-a.mcap: the log is incomplete (4211 messages, to 96.250 s); "
        "graded as far as it goes"
    )
    note = incomplete_note("p" * 20, problem, "graded")  # the shorter form is too long
    assert "(read 4211 messages)" in note and len(note) <= WIDTH
    huge = incomplete_note("q" * 150, problem, "graded")
    assert "\n" not in huge and "(read 4211 messages)" in huge  # the path is kept whole
