"""code/report_pdf: the report's flags (pages, sections, C++ code, spelling); the handout is
no report."""

from __future__ import annotations

import shutil
from pathlib import Path

import codetools
import pytest

from usar_replay.code.report_pdf import cpp_lines, report, sections, words
from usar_replay.code.sources import read_submission

needs = pytest.mark.skipif(
    shutil.which("pdftotext") is None or shutil.which("hunspell") is None,
    reason="needs poppler-utils and hunspell",
)


def test_sections_code_and_words_from_text() -> None:
    pages = codetools.REPORT_PAGES
    assert sections(pages) == ["Introduction", "Approach", "Challenges", "Resources"]
    assert cpp_lines(pages) == (4, "page 2")
    assert cpp_lines(["Then the explorer turns; it stops at each marker."]) == (0, "")
    assert words("ROS and rviz use catkin_make at /tmp/x, ArUco 3D solvd") == [
        "and", "rviz", "use", "solvd"
    ]  # fmt: skip


@needs
def test_the_reports_flags(tmp_path: Path) -> None:
    team = tmp_path / "team"
    codetools.beta(team / "final_project")
    codetools.pdf(team / "report" / "group1.pdf", codetools.REPORT_PAGES)
    got = report(read_submission(team))
    assert got.file == "report/group1.pdf" and got.pages == 3
    assert got.missing_sections == ("Contributions",)
    assert got.cpp_code is True and got.cpp_where == "page 2"
    assert set(got.misspelled) == {"solvd", "wiht"}
    assert got.spelling_per_page == round(2 / 3, 2)


@needs
def test_the_handout_the_template_ships_is_not_a_report(tmp_path: Path) -> None:
    pkg = codetools.beta(tmp_path / "t")
    codetools.pdf(pkg / "doc" / "final_project_fall2021.pdf", codetools.HANDOUT_PAGES)
    assert report(read_submission(pkg)).file is None


def test_no_pdf_is_no_report(tmp_path: Path) -> None:
    got = report(read_submission(codetools.beta(tmp_path / "t")))
    assert got.file is None and got.pages is None


def test_without_pdftotext_it_says_what_to_install(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    pkg = codetools.beta(tmp_path / "t")
    (pkg / "r.pdf").write_bytes(b"%PDF-1.4\n")
    monkeypatch.setenv("PATH", "/nonexistent")
    got = report(read_submission(pkg))
    assert got.problems == ("pdftotext is not installed: apt-get install poppler-utils",)


def test_a_pdf_over_the_size_read_is_said(tmp_path: Path) -> None:
    pkg = codetools.beta(tmp_path / "t")
    with open(pkg / "huge.pdf", "wb") as f:  # sparse: no disk used
        f.truncate(65 * 1024 * 1024)
    got = report(read_submission(pkg))
    assert got.file is None
    assert got.problems == (f"huge.pdf: {65 * 1024 * 1024} bytes, over the 67108864 read",)


@needs
def test_doxygens_pdfs_are_not_the_report_and_a_named_report_comes_first(tmp_path: Path) -> None:
    team = tmp_path / "team"
    pkg = codetools.beta(team / "final_project")
    codetools.pdf(pkg / "doc" / "latex" / "dir_3de2_dep.pdf", ["src"])
    codetools.pdf(team / "slides.pdf", ["Our demo day slides"])
    codetools.pdf(team / "Final_Report_G5.pdf", codetools.REPORT_PAGES)
    assert report(read_submission(team)).file == "Final_Report_G5.pdf"


@needs
def test_a_ligature_is_its_letters(tmp_path: Path) -> None:
    """pdftotext gives U+FB01 for "fi": read as its letters, a typo in a word with one is
    still found (it was dropped: "\ufb01" is no ASCII letter)."""
    pkg = codetools.beta(tmp_path / "t")
    codetools.pdf(pkg / "report.pdf", ["1 Introduction\nThe \ufb01ducal marker is found."])
    got = report(read_submission(pkg))
    assert got.misspelled == ("fiducal",)


@needs
def test_six_long_pdfs_are_chosen_among_by_first_page_within_the_budget(tmp_path: Path) -> None:
    """Six PDFs of 1,500 pages sharing one content stream (a full pdftotext of each: tens of
    seconds): at most the budget's PDFs are looked at, by page count and first page, the one
    whose first page reads as a report is the one read, its first READ_PAGES pages only, and
    the PDFs left are said (issue 50)."""
    from usar_replay.code.budget import Budget, spending

    team = tmp_path / "team"
    codetools.beta(team / "final_project")
    for n in range(5):
        codetools.many_pages_pdf(team / "doc" / f"notes{n}.pdf", 1500)
    codetools.many_pages_pdf(team / "doc" / "Group 7.pdf", 1500, "Approach")  # smallest: last
    sub = read_submission(team)
    with spending(Budget(pdfs=6)) as spend:
        got = report(sub)
    assert got.file == "doc/Group 7.pdf" and got.pages == 1500
    assert "doc/Group 7.pdf: the first 30 of its 1500 pages read" in got.problems
    assert spend.calls == 6 * 2 + 2  # pdfinfo and one page each; the chosen read; hunspell
    with spending(Budget(pdfs=3)) as spend:
        got = report(sub)
    assert spend.spent == "its 3 PDFs tried" and spend.calls == 3 * 2 + 2
    assert "3 more PDFs not tried (a team's budget: 3 PDFs), first doc/notes3.pdf" in got.problems
    assert got.file == "doc/notes0.pdf"  # the report was not among the PDFs tried


@needs
def test_a_pdf_poppler_cannot_read_is_said_and_passed_over(tmp_path: Path) -> None:
    pkg = codetools.beta(tmp_path / "t")
    (pkg / "report.pdf").write_bytes(b"%PDF-1.4\nnot a pdf\n")
    codetools.pdf(pkg / "doc" / "mine.pdf", codetools.REPORT_PAGES)
    got = report(read_submission(pkg))
    assert got.file == "doc/mine.pdf"
    assert got.problems[0].startswith("report.pdf: pdfinfo could not read it (exit ")
