"""code/cxx: comments told from code, strings and raw strings never comments."""

from __future__ import annotations

from usar_replay.code.cxx import code_only, comments


def test_line_and_block_comments_each_line_with_its_number() -> None:
    text = 'int a = 1;  // one\n/* two\n * three */\nint b;\n'
    got = [(c.line, c.text, c.block) for c in comments(text)]
    assert got == [(1, "one", False), (2, "two", True), (3, "three", True)]


def test_strings_hold_no_comment() -> None:
    text = 'auto u = "http://x/*y*/";\nauto r = R"(// not one)";\nchar c = \'/\'; // real\n'
    assert [c.text for c in comments(text)] == ["real"]


def test_doc_comments_are_marked() -> None:
    text = "/// brief\n//! also\n/** block */\n// plain\n"
    assert [c.doc for c in comments(text)] == [True, True, True, False]


def test_code_only_keeps_lines_and_blanks_comments() -> None:
    text = "int a; // x\n/* y\n z */ int b;\n"
    out = code_only(text)
    assert out.count("\n") == text.count("\n")
    assert "x" not in out and "y" not in out and "int b;" in out


def test_an_unterminated_comment_runs_to_the_end() -> None:
    assert [c.text for c in comments("int a;\n/* never closed\nint b;")] == [
        "never closed", "int b;"
    ]  # fmt: skip
