"""`usar code` (cli/commands/code): the table, the JSON and CSV, exit codes, a missing tool
said in one line with the lines that need it."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import codetools
import pytest

from usar_replay.cli.main import main

TOOLS = ("doxygen", "cppcheck", "clang-format", "g++", "pdftotext", "pdfinfo", "hunspell")
pytestmark = pytest.mark.skipif(
    any(shutil.which(t) is None for t in TOOLS), reason="needs the code grade's tools"
)


def _class(root: Path) -> Path:
    codetools.alpha(root / "alpha")
    codetools.copy_of_alpha(root / "copy")
    codetools.beta(root / "beta")
    return root


def test_a_class_graded_with_its_outputs(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    root = _class(tmp_path / "class")
    tmpl = codetools.template(tmp_path / "template")
    out = tmp_path / "out"
    code = main(["code", str(root), "--template", str(tmpl), "--json", f"{out}.json",
                 "--csv", f"{out}.csv", "--html", f"{out}.html", "--jobs", "2"])  # fmt: skip
    text = capsys.readouterr().out
    assert code == 0
    assert "alpha (final_project): 57/57 points" in text
    assert all(len(line) <= 100 for line in text.splitlines())
    doc = json.loads(Path(f"{out}.json").read_text())
    assert doc["format"] == "usar-code/1" and doc["template"] == str(tmpl)
    assert [(p["a"], p["b"]) for p in doc["similar"]] == [("alpha", "copy")]
    assert Path(f"{out}.csv").read_text().startswith("format,team,package")
    assert "alpha ~ copy" in Path(f"{out}.html").read_text()


def test_a_missing_tool_is_one_line_and_its_lines_say_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    for tool in TOOLS:
        if tool != "doxygen":
            os.symlink(shutil.which(tool) or "", bin_dir / tool)
    monkeypatch.setenv("PATH", str(bin_dir))
    pkg = codetools.alpha(tmp_path / "alpha")
    assert main(["code", str(pkg), "--json", str(tmp_path / "g.json")]) == 1
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    assert err == [
        "usar code: doxygen is not installed: apt-get install doxygen; 4 rubric lines not scored"
    ]
    assert all(len(line) <= 100 for line in err)
    doc = json.loads((tmp_path / "g.json").read_text())
    lines = {x["id"]: x for x in doc["packages"][0]["lines"]}
    assert lines["doc_coverage"]["points"] is None
    assert lines["doc_coverage"]["note"] == "doxygen is not installed: apt-get install doxygen"
    assert lines["unused_functions"]["points"] == 4  # cppcheck was there


@pytest.mark.parametrize(
    ("args", "said"),
    [
        (["--jobs", "0"], "--jobs 0: give 1 or more"),
        (["--rubric", "/nonexistent.toml"], "--rubric /nonexistent.toml: cannot be read"),
        (["--template", "/nonexistent"], "--template /nonexistent: "),
    ],
)
def test_usage_errors_are_one_line_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], said: str
) -> None:
    pkg = codetools.beta(tmp_path / "b")
    assert main(["code", str(pkg), *args]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and said in err and "Traceback" not in err


def test_no_such_folder(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["code", str(tmp_path / "none")]) == 2
    assert "no such folder" in capsys.readouterr().err


def test_an_output_that_exists_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pkg = codetools.beta(tmp_path / "b")
    (tmp_path / "g.json").write_text("{}")
    assert main(["code", str(pkg), "--json", str(tmp_path / "g.json")]) == 2
    assert "--overwrite" in capsys.readouterr().err


def test_hostile_folders_are_their_teams_verdicts(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A huge (sparse) file, a link out, a binary and a non-UTF-8 source: each is that team's
    finding or verdict; every other team is graded, nothing crashes or hangs (exit 1)."""
    root = tmp_path / "class"
    codetools.alpha(root / "good")
    huge = codetools.beta(root / "huge")
    with open(huge / "src" / "blob.bin", "wb") as f:
        f.truncate(300 * 1024 * 1024)
    linked = codetools.beta(root / "linked")
    os.symlink("/etc/shadow", linked / "src" / "secret.h")
    odd = codetools.beta(root / "odd")
    (odd / "src" / "bin.cpp").write_bytes(b"\x7fELF\0\0\0")
    (odd / "src" / "latin.cpp").write_bytes(b"// \xe9t\xe9\nint x;\n")
    json_path = tmp_path / "g.json"
    assert main(["code", str(root), "--json", str(json_path)]) == 1
    text = capsys.readouterr().out
    doc = json.loads(json_path.read_text())
    verdicts = {p["team"]: p["verdict"] for p in doc["packages"]}
    assert verdicts == {"good": "graded", "huge": "unreadable", "linked": "unreadable",
                        "odd": "graded"}  # fmt: skip
    odd_pkg = next(p for p in doc["packages"] if p["team"] == "odd")
    assert any("bin.cpp: binary" in f for f in odd_pkg["findings"])
    assert any("latin.cpp: not UTF-8" in f for f in odd_pkg["findings"])
    assert "huge (no package): 0/60 points, unreadable" in text
    assert "a link leaving" in text and "/etc/shadow" in text


def test_file_names_that_are_not_utf8_are_shown_escaped(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A name that is not UTF-8 (an old zip's ``caf\\xe9.cpp``) or holds a control character
    is escaped in every output: the JSON is written, never a UnicodeEncodeError."""
    pkg = codetools.beta(tmp_path / "t")
    src = os.fsencode(pkg / "src")
    with open(os.path.join(src, b"caf\xe9.cpp"), "wb") as f:
        f.write(b"int unused_fn(int a) { return a; }\n// foo();\n// bar(1);\n")
    with open(os.path.join(src, b"rtl\xe2\x80\xaeppc.cpp"), "wb") as f:
        f.write(b"int x2;\n")
    assert main(["code", str(pkg), "--json", str(tmp_path / "g.json"),
                 "--csv", str(tmp_path / "g.csv")]) == 0  # fmt: skip
    text = capsys.readouterr().out
    assert "src/caf\\xe9.cpp:2" in text and "\u202e" not in text
    doc = json.loads((tmp_path / "g.json").read_text(encoding="utf-8"))
    assert doc["packages"][0]["evidence"]["unused_functions"].startswith(
        "src/caf\\xe9.cpp:1 unused_fn"
    )


def test_a_missing_report_tool_is_said_too(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    for tool in TOOLS:
        if tool != "hunspell":
            os.symlink(shutil.which(tool) or "", bin_dir / tool)
    monkeypatch.setenv("PATH", str(bin_dir))
    pkg = codetools.beta(tmp_path / "t")
    codetools.pdf(pkg / "report.pdf", codetools.REPORT_PAGES)
    assert main(["code", str(pkg)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        "usar code: hunspell is not installed: apt-get install hunspell hunspell-en-us; report "
        "flags partial"
    ]
    assert len(err[0]) <= 100


def test_a_class_of_linked_team_folders_says_they_are_links(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Team folders that are links are never read through: one line saying so and what to do
    (exit 2, as any usage error), the words ``usar batch`` gives such a team."""
    real = _class(tmp_path / "real")
    links = tmp_path / "class"
    links.mkdir()
    for team in ("alpha", "beta"):
        (links / team).symlink_to(real / team)
    assert main(["code", str(links)]) == 2
    err = capsys.readouterr().err.strip()
    assert err == (
        f"usar: error: {links}: alpha, beta are links: usar reads only real folders, never "
        "through a link; copy each in its place (cp -rL) and grade again"
    )
    assert "\n" not in err
