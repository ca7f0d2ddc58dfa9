"""`usar log` (cli/commands/log): a log's /rosout lines as ROS 2 prints its console, filtered by
level, node and sim time; ``--output``, a ROS 1 run's nodes' own output. Run on the one-room
recording of conftest (real MCAP, real messages) and on logs written by usar's writer."""

from __future__ import annotations

from pathlib import Path

import pytest
from clitools import one_error_line, usar
from logtools import rewrite

from usar_replay.cli.main import main
from usar_replay.core import contract, msgs
from usar_replay.log import bag
from usar_replay.pipeline.record import RecordResult

Room = tuple[Path, RecordResult]


def _echo(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, list[str]]:
    """``usar ARGS`` in this process: its exit code and stdout's lines."""
    code = main(list(args))
    return code, capsys.readouterr().out.splitlines()


def _t(ns: int) -> str:
    return f"{ns / 1e9:.3f}"


@pytest.fixture(scope="module")
def leveled_log(room_log: Room, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The room log with its /rosout entries at every level in turn, and one long entry of
    several lines (a traceback's shape)."""
    levels = iter([msgs.Log.DEBUG, msgs.Log.INFO, msgs.Log.WARN, msgs.Log.ERROR, msgs.Log.FATAL]
                  * 10)  # fmt: skip
    first = [True]

    def edit(m: bag.BagMessage) -> msgs.Message | None:
        if m.topic != "/rosout" or not isinstance(m.msg, msgs.Log):
            return None
        text = m.msg.msg
        if first[0]:
            first[0] = False
            text = "Traceback (most recent call last):\n  " + "word " * 40 + "\nValueError: x"
        return msgs.Log(stamp=m.msg.stamp, level=next(levels), name=m.msg.name, msg=text)

    out = tmp_path_factory.mktemp("leveled") / "leveled.mcap"
    rewrite(room_log[0], out, edit)
    return out


def _entries(path: Path) -> list[tuple[int, msgs.Log]]:
    got = [(m.log_time_ns, m.msg) for m in bag.BagReader(path).messages(["/rosout"])]
    return [(t, m) for t, m in got if isinstance(m, msgs.Log)]


def test_log_prints_time_level_node_and_text(
    room_log: Room, capsys: pytest.CaptureFixture[str]
) -> None:
    code, lines = _echo(capsys, "log", str(room_log[0]))
    assert code == 0
    entries = _entries(room_log[0])
    assert len(entries) > 5
    assert lines == [f"[INFO] [{_t(t)}] [{m.name}]: {m.msg}" for t, m in entries]


def test_log_filters_by_level_node_and_time(
    leveled_log: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    entries = _entries(leveled_log)
    heads = [line for line in _echo(capsys, "log", str(leveled_log))[1] if line.startswith("[")]
    assert [h.split("]")[0] for h in heads[:5]] == ["[DEBUG", "[INFO", "[WARN", "[ERROR", "[FATAL"]
    code, lines = _echo(capsys, "log", str(leveled_log), "--level", "warn")
    assert code == 0
    assert len(lines) == sum(m.level >= msgs.Log.WARN for _, m in entries)
    assert all(line.startswith(("[WARN]", "[ERROR]", "[FATAL]")) for line in lines)
    code, lines = _echo(capsys, "log", str(leveled_log), "--node", "follower", "--since", "40")
    want = [(t, m) for t, m in entries if m.name == "follower" and t >= 40_000_000_000]
    assert code == 0 and len(lines) == len(want) > 0
    assert all(f"[{_t(t)}] [follower]: " in line for (t, _), line in zip(want, lines, strict=True))


def test_a_long_entry_goes_on_over_indented_lines(
    leveled_log: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, lines = _echo(capsys, "log", str(leveled_log), "--until", "1")
    assert code == 0
    assert lines[0].startswith("[DEBUG] [1.000] [explorer]: Traceback (most recent call last):")
    assert all(len(line) <= 100 for line in lines)
    body = lines[1 : lines.index("    ValueError: x") + 1]
    assert len(body) > 2 and all(line.startswith("    ") for line in body)
    assert " ".join(line.strip() for line in body[:-1]) == ("word " * 40).strip()


def test_log_errors_are_one_line(room_log: Room) -> None:
    out = usar("log", str(room_log[0]), "--node", "folower")
    one_error_line(out, 2, "no node folower", "explorer, follower")
    out = usar("log", str(room_log[0]), "--level", "loud")
    one_error_line(out, 2, "'loud' is not a level", "WARN")


def test_output_shows_each_nodes_kept_output(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "ros1.mcap"
    prefix = contract.NODE_OUTPUT_ATTACHMENT_PREFIX
    with bag.BagWriter(path) as w:
        w.add_attachment(prefix + "explorer.txt", "text/plain", b"explorer: up\n", 1)
        w.add_attachment(prefix + "follower.txt", "text/plain", b"follower: up\n", 1)
        w.write(contract.ROSOUT, msgs.Log(name="explorer", msg="hi"), 10**9)
    code, lines = _echo(capsys, "log", str(path), "--output", "--node", "follower")
    assert code == 0
    assert lines == ["--- /follower: stdout and stderr ---", "follower: up"]
    assert len(_echo(capsys, "log", str(path), "--output")[1]) == 4
    assert main(["log", str(path), "--output", "--level", "warn"]) == 2
    assert "no --level, --since, --until" in capsys.readouterr().err
