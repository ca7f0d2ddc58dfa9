"""viewer/viewer_process: where a view goes, the command that opens it, and the addresses the
viewer's servers are reached at (the viewer itself, started and stopped:
tests/viewer/test_view.py)."""

from __future__ import annotations

import shlex
import socket
from pathlib import Path

import pytest

from usar_replay.core.errors import UsageError
from usar_replay.viewer.viewer_process import (
    Output,
    _last_error,
    _local_host,
    _port_open,
    _shown_host,
    _url_host,
    check_rrd,
    choose_output,
    default_rrd_path,
    open_command,
)


def test_choose_output_rules(tmp_path: Path) -> None:
    log = tmp_path / "run.mcap"
    assert choose_output(log, save=None, web=False, env={"DISPLAY": ":0"}) == Output(spawn=True)
    assert choose_output(log, save=None, web=False, env={"WAYLAND_DISPLAY": "w"}).spawn
    assert choose_output(log, save=None, web=False, env={}) == Output(rrd=tmp_path / "run.rrd")
    out = tmp_path / "o.rrd"
    assert choose_output(log, save=out, web=False, env={"DISPLAY": ":0"}) == Output(rrd=out)
    assert choose_output(log, save=None, web=True, env={"DISPLAY": ":0"}) == Output(web=True)
    assert default_rrd_path("runs/course.mcap") == Path("runs/course.rrd")


def test_an_rrd_may_not_replace_the_log_or_a_file(tmp_path: Path) -> None:
    log = tmp_path / "run.mcap"
    log.write_bytes(b"log")
    with pytest.raises(UsageError, match="is an input"):
        check_rrd(log, log, overwrite=True)
    (tmp_path / "old.rrd").write_bytes(b"old")
    with pytest.raises(UsageError, match=r"--save .*old.rrd: exists; pass --overwrite"):
        check_rrd(tmp_path / "old.rrd", log, overwrite=False)
    check_rrd(tmp_path / "old.rrd", log, overwrite=True)


def test_the_open_command_quotes_the_path() -> None:
    words = shlex.split(open_command("/runs/a run.rrd"))
    assert words[-1] == "/runs/a run.rrd" and words[0].endswith("rerun")


def test_addresses_for_the_browser_and_for_this_machine() -> None:
    assert _local_host("0.0.0.0") == "127.0.0.1" and _local_host("::") == "127.0.0.1"
    assert _local_host("192.168.1.5") == "192.168.1.5"
    assert _url_host("::1") == "[::1]" and _url_host("127.0.0.1") == "127.0.0.1"
    assert _shown_host("127.0.0.1") == "localhost" and _shown_host("::1") == "localhost"
    assert _shown_host("0.0.0.0") == socket.gethostname()
    assert _shown_host("10.0.0.7") == "10.0.0.7"


def test_a_listening_port_is_seen_and_a_closed_one_is_not() -> None:
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen()
        port = server.getsockname()[1]
        assert _port_open("127.0.0.1", port)
    assert not _port_open("127.0.0.1", port)


def test_the_viewers_own_reason_is_its_last_error_line() -> None:
    text = "starting\n[ERROR winit] Error: Failed to open connection to X server\nbye\n"
    assert _last_error(text) == "Failed to open connection to X server"
    assert _last_error("all fine\n") == ""
