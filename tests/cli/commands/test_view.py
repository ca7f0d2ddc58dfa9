"""`usar view` (cli/commands/view): what is refused before any work, each one line and exit 2
(a wrong path, an output over the log or over a file, a folder, a bad port or address). What a
view holds and the web server: tests/viewer/test_view.py."""

from __future__ import annotations

from pathlib import Path

import pytest
from clitools import no_display, one_error_line, usar

from usar_replay.pipeline.record import RecordResult


def test_cli_missing_file_is_one_line_exit_2(tmp_path: Path) -> None:
    out = tmp_path / "never.rrd"
    done = usar("view", str(tmp_path / "missing.mcap"), "--save", str(out), env=no_display())
    assert done.returncode == 2  # a wrong path is a usage error
    assert done.stderr.count("\n") == 1 and "no such file" in done.stderr
    assert "Traceback" not in done.stderr
    assert not out.exists() and not out.with_name("never.rrd.part").exists()
    assert list(tmp_path.iterdir()) == []


def test_cli_never_writes_over_the_log(room_log: tuple[Path, RecordResult], tmp_path: Path) -> None:
    log = tmp_path / "a.mcap"
    log.write_bytes(room_log[0].read_bytes())
    before = log.read_bytes()
    for extra in ([], ["--overwrite"]):
        done = usar("view", str(log), "--save", str(log), *extra)
        one_error_line(done, 2, "--save", "input")
    same = usar("view", str(log), "--save", str(tmp_path / "." / "a.mcap"))
    one_error_line(same, 2, "input")
    assert log.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.mcap"]


def test_cli_default_output_next_to_the_log_is_not_replaced(
    room_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    log = tmp_path / "run.mcap"
    log.write_bytes(room_log[0].read_bytes())
    (tmp_path / "run.rrd").write_bytes(b"kept")
    done = usar("view", str(log), env=no_display())
    one_error_line(done, 2, "run.rrd", "exists", "--overwrite")
    assert (tmp_path / "run.rrd").read_bytes() == b"kept"


def test_cli_save_to_a_directory_is_one_line(
    room_log: tuple[Path, RecordResult], tmp_path: Path
) -> None:
    target = tmp_path / "views"
    target.mkdir()
    done = usar("view", str(room_log[0]), "--save", str(target))
    one_error_line(done, 2, "--save", "directory")
    assert list(target.iterdir()) == [] and sorted(tmp_path.iterdir()) == [target]


@pytest.mark.parametrize(
    "option", [["--web-port", "99999"], ["--grpc-port", "0"], ["--web-port", "http"]]
)
def test_cli_ports_are_checked_by_the_parser(
    room_log: tuple[Path, RecordResult], option: list[str]
) -> None:
    done = usar("view", str(room_log[0]), "--web", *option)
    assert done.returncode == 2
    assert "Traceback" not in done.stderr
    last = done.stderr.strip().splitlines()[-1]
    assert option[0] in last and "1-65535" in last


def test_cli_bind_takes_an_ip_address(room_log: tuple[Path, RecordResult]) -> None:
    done = usar("view", str(room_log[0]), "--web", "--bind", "example.org")
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert "--bind" in done.stderr.strip().splitlines()[-1]
