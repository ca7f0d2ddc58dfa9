"""code/classgrade: teams found in the paths, each graded, copies listed, bad folders said."""

from __future__ import annotations

import os
from pathlib import Path

import codetools
import pytest

from usar_replay.code.classgrade import grade_class, teams
from usar_replay.code.rubric import default_rubric
from usar_replay.code.template import read_template
from usar_replay.core.errors import UsageError
from usar_replay.core.folder_walk import linked


def _class(root: Path) -> Path:
    for name in ("alpha", "copy_of_alpha", "beta", "procedural", "borrowed"):
        getattr(codetools, name)(root / name)
    return root


def test_a_class_folder_is_its_teams(tmp_path: Path) -> None:
    root = _class(tmp_path / "class")
    (root / "_notes").mkdir()
    got = [name for name, _ in teams([str(root)])]
    assert got == ["alpha", "beta", "borrowed", "copy_of_alpha", "procedural"]
    assert [n for n, _ in teams([str(root / "beta"), str(root / "alpha")])] == ["alpha", "beta"]
    with pytest.raises(UsageError, match="no such folder"):
        teams([str(tmp_path / "none")])


def test_the_copy_is_listed_and_the_honest_pairs_are_not(tmp_path: Path) -> None:
    root = _class(tmp_path / "class")
    tmpl = read_template(codetools.template(tmp_path / "tmpl"))
    done = grade_class([str(root)], default_rubric(), tmpl, jobs=2)
    assert [(p.a, p.b) for p in done.similar] == [("alpha", "copy_of_alpha")]
    assert [g.team for g in done.grades] == sorted(g.team for g in done.grades)


def test_a_team_with_a_fifo_is_its_verdict_not_the_end(tmp_path: Path) -> None:
    root = tmp_path / "class"
    codetools.alpha(root / "alpha")
    codetools.beta(root / "bad")
    os.mkfifo(root / "bad" / "src" / "x.cpp")
    done = grade_class([str(root)], default_rubric())
    verdicts = {g.team: g.verdict for g in done.grades}
    assert verdicts == {"alpha": "graded", "bad": "unreadable"}
    bad = next(g for g in done.grades if g.team == "bad")
    assert "not a regular file" in bad.findings[0]


def test_a_class_where_one_team_has_no_package_is_still_a_class(tmp_path: Path) -> None:
    root = tmp_path / "class"
    codetools.alpha(root / "alpha")
    codetools.beta(root / "beta")
    (root / "python_team").mkdir()
    (root / "python_team" / "mission.py").write_text("def main() -> None: ...\n")
    assert [n for n, _ in teams([str(root)])] == ["alpha", "beta", "python_team"]
    repo = tmp_path / "repo"
    codetools.alpha(repo / "catkin_ws" / "src" / "final_project")
    (repo / "docs").mkdir()
    assert teams([str(repo)]) == [("repo", repo)]


def test_a_linked_team_folder_is_its_verdict_in_the_batchs_words(tmp_path: Path) -> None:
    """A class folder's team that is a link is never read through (it could lead anywhere):
    that team's verdict, saying so in the words ``usar batch`` uses; a path given on the
    command line is the grader's own, read where it leads."""
    real = tmp_path / "real"
    codetools.alpha(real / "elsewhere")
    root = tmp_path / "class"
    codetools.alpha(root / "alpha")
    codetools.beta(root / "beta")
    (root / "linked").symlink_to(real / "elsewhere")
    assert [n for n, _ in teams([str(root)])] == ["alpha", "beta", "linked"]
    done = grade_class([str(root)], default_rubric())
    bad = next(g for g in done.grades if g.team == "linked")
    assert bad.verdict == "unreadable" and bad.points == 0
    assert bad.findings == (linked(["linked"]),)
    assert bad.findings[0].startswith("linked is a link: usar reads only real folders")
    assert teams([str(root / "linked")]) == [("elsewhere", (real / "elsewhere").resolve())]
    only_links = tmp_path / "links"
    only_links.mkdir()
    (only_links / "a").symlink_to(root / "alpha")
    (only_links / "b").symlink_to(root / "beta")
    with pytest.raises(UsageError, match=r"links: a, b are links: usar reads only real folders"):
        teams([str(only_links)])


def test_a_committed_catkin_workspace_is_graded_without_catkins_link(tmp_path: Path) -> None:
    """Every ``catkin_make`` workspace has ``src/CMakeLists.txt`` -> catkin's
    ``toplevel.cmake``: catkin's link, left out and said; the team is graded on the rest, as
    ``usar batch`` reads it; any other link out is still the team's verdict (issue 51)."""
    root = _class(tmp_path / "class")
    ws = tmp_path / "class" / "workspace"
    (ws / "src").mkdir(parents=True)
    os.rename(root / "beta", ws / "src" / "beta")
    (ws / "src" / "CMakeLists.txt").symlink_to("/opt/ros/noetic/share/catkin/cmake/toplevel.cmake")
    done = grade_class([str(root)], default_rubric(), jobs=2)
    [team] = [g for g in done.grades if g.team == "workspace"]
    assert team.verdict == "graded" and team.points > 0
    assert "src/CMakeLists.txt: catkin's link out of the workspace, left out" in team.findings
    (ws / "src" / "CMakeLists.txt").unlink()
    (ws / "src" / "CMakeLists.txt").symlink_to("/etc/hostname")
    done = grade_class([str(root)], default_rubric(), jobs=2)
    [team] = [g for g in done.grades if g.team == "workspace"]
    assert team.verdict == "unreadable" and "a link leaving" in team.findings[0]


def test_a_team_of_six_long_pdfs_is_graded_within_its_budget_with_the_verdict_line(
    tmp_path: Path,
) -> None:
    """Six PDFs of 1,500 pages (issue 50: 181 s for that team): the team's grade ends within
    its budget, the first of its findings saying what was spent; the other team is graded."""
    import time

    from usar_replay.code.budget import DEFAULT

    root = _class(tmp_path / "class")
    for n in range(6):
        codetools.many_pages_pdf(root / "beta" / "doc" / f"part{n}.pdf", 1500)
    start = time.monotonic()
    done = grade_class([str(root / "alpha"), str(root / "beta")], default_rubric(), jobs=2)
    assert time.monotonic() - start < DEFAULT.wall_s
    beta = next(g for g in done.grades if g.team == "beta")
    assert beta.verdict == "graded"
    assert beta.findings[0].startswith(
        f"budget spent: its {DEFAULT.pdfs} PDFs tried (of {DEFAULT.words()})"
    )
    assert beta.report is not None and beta.report.pages == 1500
    alpha = next(g for g in done.grades if g.team == "alpha")
    assert not any(f.startswith("budget spent") for f in alpha.findings)


def _descendants(pid: int) -> dict[int, str]:
    """Every process below ``pid`` (pid -> its command line), read from /proc."""
    parents: dict[int, int] = {}
    names: dict[int, str] = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
            cmd = (entry / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        parents[int(entry.name)] = int(stat.rsplit(")", 1)[1].split()[1])
        names[int(entry.name)] = cmd
    out, todo = {}, [pid]
    while todo:
        p = todo.pop()
        for child, parent in parents.items():
            if parent == p:
                out[child] = names[child]
                todo.append(child)
    return out


def test_sigterm_ends_usar_code_and_its_running_tool_within_2_s(tmp_path: Path) -> None:
    """A PDF whose first page takes pdftotext ~30 s: SIGTERM while it runs ends ``usar code``
    (exit 143) within 2 s, and the tool with it (issue 50: it went on for more than 5 s)."""
    import signal
    import time

    from clitools import start_usar

    team = codetools.beta(tmp_path / "team")
    codetools.many_pages_pdf(team / "report.pdf", 3, "Report", slow_first=40)
    proc = start_usar("code", str(team))
    deadline = time.monotonic() + 60
    tool: dict[int, str] = {}
    while not tool and proc.poll() is None and time.monotonic() < deadline:
        tool = {p: c for p, c in _descendants(proc.pid).items() if "pdftotext" in c}
    assert tool, "pdftotext never ran"
    proc.send_signal(signal.SIGTERM)
    sent = time.monotonic()
    proc.wait(timeout=10)
    took = time.monotonic() - sent
    _, err = proc.communicate()
    assert proc.returncode == 143, err
    assert took < 2.0, f"{took:.1f} s"
    assert "usar: terminated by SIGTERM" in err and "Traceback" not in err
    ends = time.monotonic() + 1.0  # the sandbox's inner processes die with its outer one
    while _running(tool) and time.monotonic() < ends:
        pass
    assert not _running(tool), "the tool outlived usar"


def _running(pids: dict[int, str]) -> list[int]:
    """Those of ``pids`` that still run (a zombie no longer does: nobody has reaped it)."""
    out = []
    for p in pids:
        try:
            state = Path(f"/proc/{p}/stat").read_text().rsplit(")", 1)[1].split()[0]
        except OSError:
            continue
        if state != "Z":
            out.append(p)
    return out


def test_a_team_past_its_calls_scores_0_on_the_lines_cut_and_says_so(tmp_path: Path) -> None:
    """Past its tool calls, each later tool of that team is refused at once: its lines score 0
    as a tool past its own limit does, each note saying the budget, and the verdict line
    first among its findings."""
    from usar_replay.code.budget import Budget
    from usar_replay.code.grade import Options

    root = _class(tmp_path / "class")
    opts = Options(budget=Budget(tool_calls=1))
    done = grade_class([str(root / "beta")], default_rubric(), options=opts)
    [beta] = done.grades
    assert beta.verdict == "graded"
    assert beta.findings[0].startswith("budget spent: its 1 tool calls (of 1 tool calls, ")
    cut = [s for s in beta.lines if "the team's budget (its 1 tool calls)" in s.note]
    assert cut and all(s.points == 0 for s in cut)
