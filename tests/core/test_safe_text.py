"""core/safe_text: mission text is printed with its control characters shown, never obeyed."""

from __future__ import annotations

from pathlib import Path

import pytest

from usar_replay.core.safe_text import (
    csv_cell,
    csv_row,
    html_text,
    json_data,
    safe,
    safe_copy,
    safe_line,
)


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


# -- one helper per medium (issue 50, findings 5 and 6) ---------------------------------------

HOSTILE = '=HYPERLINK("https:\\\\evil.invalid","open")\x1b[2J\x9b1m\u202e\u2028'


@pytest.mark.parametrize(
    ("raw", "cell"),
    [
        (
            '=HYPERLINK("https:\\\\evil.invalid","open")',
            '\'=HYPERLINK("https:\\\\evil.invalid","open")',
        ),
        ("+cmd|' /C calc'!A0", "'+cmd|' /C calc'!A0"),
        ("-2+3+cmd|' /C calc'!A0", "'-2+3+cmd|' /C calc'!A0"),
        ("@SUM(1+1)", "'@SUM(1+1)"),
        ("\t=1", "\\x09=1"),  # shown, so it no longer begins a cell with a tab
        ("\r=1", "\\x0d=1"),
        ("-0.5", "-0.5"),  # a plain number stays a number
        ("+12", "+12"),
        ("1e-3", "1e-3"),
        ("team a", "team a"),
    ],
)
def test_a_csv_cell_never_begins_a_formula(raw: str, cell: str) -> None:
    assert csv_cell(raw) == cell


def test_a_csv_row_escapes_controls_and_keeps_numbers() -> None:
    row = csv_row([HOSTILE, 3, 0.5, None, "ok"])
    assert row[1:] == [3, 0.5, None, "ok"]
    assert isinstance(row[0], str) and row[0].startswith("'=") and row[0].isprintable()


def test_html_text_escapes_markup_quotes_and_controls() -> None:
    shown = html_text("<b onmouseover='x'>\x1b[2J\u202e</b>\nnext")
    assert shown == ("&lt;b onmouseover=&#x27;x&#x27;&gt;\\x1b[2J\\u202e&lt;/b&gt;\nnext")
    assert "\n" not in html_text("a\nb", lines=False)


def test_json_data_leaves_no_control_in_any_string_decoded_or_not() -> None:
    import json

    doc = {"out" + HOSTILE: [HOSTILE, {"k": HOSTILE}, 1, 2.5, True, None], "t": "a\n\tb"}
    text = json.dumps(json_data(doc), ensure_ascii=False)
    back = json.loads(text)
    for s in [text, *back, *back["out" + safe(HOSTILE)], back["out" + safe(HOSTILE)][1]["k"]]:
        assert all(safe(ch) == ch or ch in "\n\t" for ch in str(s)), s
    assert back["t"] == "a\n\tb"  # newline and tab are JSON's to escape, and stay in the text
    assert back["out" + safe(HOSTILE)][2:] == [1, 2.5, True, None]


def test_safe_copy_escapes_a_file_of_any_size_a_block_at_a_time(tmp_path: Path) -> None:
    raw = ("ok \x1b[2J\u202e é\n\t" * 100_000).encode() + b"\xff end\n"  # 1.5 MB, two blocks
    (tmp_path / "out.txt").write_bytes(raw)
    safe_copy(tmp_path / "out.txt", tmp_path / "shown.txt")
    shown = (tmp_path / "shown.txt").read_text(encoding="utf-8")
    assert shown == ("ok \\x1b[2J\\u202e é\n\t" * 100_000) + "\ufffd end\n"
