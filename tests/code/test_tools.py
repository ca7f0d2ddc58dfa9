"""code/tools: a tool runs on a copy with limits; a missing one names its Debian package."""

from __future__ import annotations

from pathlib import Path

import pytest

from usar_replay.code.tools import (
    DEBIAN,
    OUTPUT_CAP,
    Ran,
    ToolLimits,
    missing,
    run_tool,
    write_copy,
)


def test_a_missing_tool_names_its_debian_package(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("PATH", "/nonexistent")
    for tool, pkg in DEBIAN.items():
        assert missing(tool) == f"{tool} is not installed: apt-get install {pkg}"


def test_an_installed_tool_is_not_missing() -> None:
    assert missing("sh") == ""


def test_a_tool_past_its_wall_limit_is_said(tmp_path: Path) -> None:
    ran = run_tool(["sh", "-c", "while :; do :; done"], tmp_path, ToolLimits(wall_s=1))
    assert ran.limit == "its 1 s wall limit"


def test_the_file_size_limit_holds(tmp_path: Path) -> None:
    ran = run_tool(["sh", "-c", "head -c 3000000 /dev/zero > big"], tmp_path,
                   ToolLimits(file_mb=1), sandbox=False)  # fmt: skip
    assert ran.code != 0
    assert (tmp_path / "big").stat().st_size <= 1024 * 1024


def test_output_comes_back_and_the_copy_stays_inside(tmp_path: Path) -> None:
    write_copy([("src/a.cpp", "int a;\n"), ("../escape.cpp", "x")], tmp_path / "w")
    assert (tmp_path / "w" / "src" / "a.cpp").read_text() == "int a;\n"
    assert not (tmp_path / "escape.cpp").exists()
    ran = run_tool(["cat", "src/a.cpp"], tmp_path / "w")
    assert (ran.code, ran.output, ran.limit) == (0, "int a;\n", "")


def test_the_tools_output_says_when_it_was_cut(tmp_path: Path) -> None:
    ran = run_tool(["head", "-c", str(OUTPUT_CAP + 10), "/dev/zero"], tmp_path)
    assert ran.cut and len(ran.output) == OUTPUT_CAP
    assert not run_tool(["echo", "hi"], tmp_path).cut


def test_stop_all_ends_a_running_tool_and_refuses_the_next(tmp_path: Path) -> None:
    """On a signal, ``usar code`` calls stop_all: the running tool's process group is killed
    at once (not at its 30 s limit) and no tool starts after it."""
    import threading
    import time

    from usar_replay.code import tools

    got: list[Ran] = []
    worker = threading.Thread(
        target=lambda: got.append(run_tool(["sleep", "30"], tmp_path, sandbox=False))
    )
    worker.start()
    while not tools._LIVE:  # the tool is running
        time.sleep(0.01)
    start = time.monotonic()
    try:
        tools.stop_all()
        worker.join(timeout=10)
        assert time.monotonic() - start < 2.0
        assert got[0].limit == "usar's stop (a signal)"
        assert run_tool(["true"], tmp_path, sandbox=False).limit == "usar's stop (a signal)"
    finally:
        tools._resume()
    assert run_tool(["true"], tmp_path, sandbox=False).limit == ""
