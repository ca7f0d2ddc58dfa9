"""`usar info` (cli/commands/info): a recording's report and its exit code, on real logs."""

from __future__ import annotations

from pathlib import Path

import pytest
from clitools import usar

from usar_replay.cli.main import main
from usar_replay.core import msgs
from usar_replay.log import bag

T0 = 1_000_000_000


def _log(path: Path, *, interrupted: bool = False) -> None:
    w = bag.BagWriter(path)
    w.add_metadata(bag.RUN_METADATA, {"camera": "640x480@10"})
    for i in range(30):
        t = T0 + i * 100_000_000
        w.write("/explorer/cmd_vel", msgs.Twist(angular=msgs.Vector3(z=0.1)), t)
        w.write("/rosout", msgs.Log(stamp=msgs.Time.from_ns(t), level=20, msg=f"tick {i}"), t)
    w.close("interrupted" if interrupted else "complete")


def test_info_reports_topics_counts_duration(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "run.mcap"
    _log(path)
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "/explorer/cmd_vel" in out and "geometry_msgs/msg/Twist" in out
    assert "/rosout" in out and "rcl_interfaces/msg/Log" in out
    assert "Duration:      2.900 s" in out
    assert "File state:    complete" in out
    assert "camera = 640x480@10" in out


def test_info_on_an_interrupted_log_exits_3(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "run.mcap"
    _log(path, interrupted=True)
    assert main(["info", str(path)]) == 3
    assert "interrupted" in capsys.readouterr().out


def test_info_on_a_truncated_log_says_how_far(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    _log(path)
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(path.read_bytes()[:-300])
    out = usar("info", str(cut))
    assert out.returncode == 3
    assert "INCOMPLETE" in out.stdout and "messages up to sim time" in out.stdout
    assert "Traceback" not in out.stderr


@pytest.mark.parametrize(
    ("content", "code"), [(None, 2), (b"", 3), (b"PK\x03\x04 a zip, not a log", 3)]
)
def test_info_on_bad_files_is_one_line(tmp_path: Path, content: bytes | None, code: int) -> None:
    path = tmp_path / "bad.mcap"
    if content is not None:
        path.write_bytes(content)
    out = usar("info", str(path))
    assert out.returncode == code  # a missing file is a usage error (2), a bad one a bad log (3)
    assert out.stdout == ""
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("usar: error: ")
    assert str(path) in lines[0]
