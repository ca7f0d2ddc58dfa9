"""core/safe_text: mission text is printed with its control characters shown, never obeyed."""

from __future__ import annotations

import pytest

from usar_replay.core.safe_text import safe, safe_line


def test_printable_text_of_any_script_is_unchanged() -> None:
    for text in ("explorer: at target_1", "Zielpunkt erreicht: ü", "目标 1", ""):
        assert safe(text) == text
        assert safe_line(text) == text


@pytest.mark.parametrize(
    ("raw", "shown"),
    [
        ("\x1b[2J", "\\x1b[2J"),  # clear the screen
        ("done\r4/4", "done\\x0d4/4"),  # carriage return over a line
        ("bell\x07", "bell\\x07"),
        ("del\x7f", "del\\x7f"),
        ("\x9b31m", "\\x9b31m"),  # C1 CSI
        ("abc\u202edef", "abc\\u202edef"),  # right-to-left override
        ("a\u2028b", "a\\u2028b"),  # line separator
        ("zero\u200dwidth", "zero\\u200dwidth"),
    ],
)
def test_control_characters_are_written_as_escapes(raw: str, shown: str) -> None:
    assert safe(raw) == shown
    assert safe_line(raw) == shown


def test_newline_and_tab_stay_in_lines_and_are_escaped_on_one_line() -> None:
    trace = "Traceback:\n\tFile x\x1b]0;title\x07"
    assert safe(trace) == "Traceback:\n\tFile x\\x1b]0;title\\x07"
    assert safe_line(trace) == "Traceback:\\x0a\\x09File x\\x1b]0;title\\x07"
    assert "\n" not in safe_line("a\nb") and "\n" in safe("a\nb")


def test_a_character_past_the_basic_plane_is_escaped_with_eight_digits() -> None:
    assert safe("\U000e0001") == "\\U000e0001"  # LANGUAGE TAG, a format character
    assert safe("\U0001f600") == "\U0001f600"  # an emoji is printable


def test_a_safe_stream_escapes_everything_written_and_is_the_stream_otherwise() -> None:
    import io

    from usar_replay.core.safe_text import SafeStream

    inner = io.StringIO()
    stream = SafeStream(inner)
    print("topic /x\x1b[2J\tcount\x9b", file=stream)
    stream.writelines(["a\x07", "b\n"])
    stream.flush()
    assert inner.getvalue() == "topic /x\\x1b[2J\tcount\\x9b\na\\x07b\n"
    assert stream.isatty() is False and stream.writable()


def test_safe_stdout_guards_stdout_for_the_block_only(capsys: pytest.CaptureFixture[str]) -> None:
    import sys

    from usar_replay.core.safe_text import safe_stdout

    with safe_stdout():
        print("title \x1b]0;pwned\x07")
    print("after \x1b[0m")
    assert capsys.readouterr().out == "title \\x1b]0;pwned\\x07\nafter \x1b[0m\n"
    assert type(sys.stdout).__name__ != "SafeStream"


def test_team_lines_split_at_newlines_only_and_cut_long_lines() -> None:
    from usar_replay.core.safe_text import team_lines

    text = "a\rb\x0cc\u2028d\tx\n" + "y" * 1000
    lines = team_lines(text, max_len=100)
    assert lines[0] == "a\\x0db\\x0cc\\u2028d   x"
    assert lines[1] == "y" * 100 + "... [900 more characters]"
    assert len(lines) == 2
