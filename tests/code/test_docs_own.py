"""code/docs_own: the committed HTML must document this package's current sources."""

from __future__ import annotations

from pathlib import Path

import codetools

from usar_replay.code.docs_own import docs_own
from usar_replay.code.sources import read_submission


def test_a_packages_own_html_is_its_own(tmp_path: Path) -> None:
    sub = read_submission(codetools.alpha(tmp_path / "a"))
    got = docs_own(sub, ["alpha::Explorer", "alpha::Follower", "alpha::Explorer::step"])
    assert got.own is True and got.files_share == 1.0 and got.names_share == 1.0
    assert got.evidence.startswith("doc/html: 4 pages")


def test_another_packages_html_is_not(tmp_path: Path) -> None:
    sub = read_submission(codetools.borrowed(tmp_path / "b"))
    got = docs_own(sub, ["Countdown", "Countdown::tick"])
    assert got.own is False
    assert got.names_share == 0.0
    assert "not documented there: " in got.evidence and "Countdown" in got.evidence


def test_stale_html_misses_the_new_files(tmp_path: Path) -> None:
    pkg = codetools.alpha(tmp_path / "a")
    (pkg / "src" / "planner.cpp").write_text("/// plans\nint plan_route() { return 1; }\n")
    (pkg / "src" / "mapper.cpp").write_text("/// maps\nint map_walls() { return 2; }\n")
    got = docs_own(read_submission(pkg), ["alpha::Explorer", "plan_route", "map_walls"])
    assert got.own is False and got.files_share == 0.6
    assert "mapper.cpp" in got.evidence


def test_no_html_is_none(tmp_path: Path) -> None:
    got = docs_own(read_submission(codetools.beta(tmp_path / "b")), ["MarkerBook"])
    assert got.own is None and got.pages == 0


def test_case_insensitive_doxygen_page_names_are_read() -> None:
    from usar_replay.code.docs_own import _page_source

    assert _page_source("_robot_8h.html") == "robot.h"
    assert _page_source("main__new_8cpp_source.html") == "main_new.cpp"
    assert _page_source("classfp_1_1_robot.html") is None
