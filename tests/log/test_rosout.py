"""log/rosout: `usar log`'s lines, from a real log written by usar's writer."""

from __future__ import annotations

from pathlib import Path

import pytest

from usar_replay.core import contract, msgs
from usar_replay.core.errors import UsageError
from usar_replay.log import bag
from usar_replay.log.rosout import LogRequest, entry_lines, level_name, level_value, lines
from usar_replay.log.run import open_run

S = 1_000_000_000


def test_level_names_and_values() -> None:
    assert level_name(msgs.Log.INFO) == "INFO"
    assert level_name(25) == "25"
    assert level_value("warn") == level_value(" WARNING ") == msgs.Log.WARN
    assert level_value("critical") == msgs.Log.FATAL
    with pytest.raises(ValueError, match="'loud' is not a level; one of DEBUG, INFO"):
        level_value("loud")


def test_an_entry_is_one_line_wrapped_and_escaped() -> None:
    entry = msgs.Log(level=msgs.Log.WARN, name="explorer", msg="stuck")
    assert entry_lines(12_350_000_000, entry) == ["[WARN] [12.350] [explorer]: stuck"]
    long = msgs.Log(level=msgs.Log.INFO, name="f", msg="word " * 30 + "\nsecond\x1b[2J")
    got = entry_lines(S, long, width=60)
    assert all(len(line) <= 60 for line in got)
    assert got[0].startswith("[INFO] [1.000] [f]: word")
    assert got[1].startswith("    word") and got[-1] == "    second\\x1b[2J"
    assert entry_lines(S, msgs.Log(name="a\nb")) == ["[0] [1.000] [a\\x0ab]:"]


@pytest.fixture
def log(tmp_path: Path) -> Path:
    path = tmp_path / "run.mcap"
    with bag.BagWriter(path) as w:
        w.add_metadata(bag.RUN_METADATA, {})
        for t, level, name, text in [
            (1, msgs.Log.INFO, "explorer", "home"),
            (2, msgs.Log.DEBUG, "follower", "tick"),
            (3, msgs.Log.WARN, "/follower", "waiting"),
            (4, msgs.Log.ERROR, "explorer", "stuck"),
        ]:
            w.write(contract.ROSOUT, msgs.Log(level=level, name=name, msg=text), t * S)
    return path


def _lines(path: Path, **kw: object) -> list[str]:
    return list(lines(open_run(path), LogRequest(**kw)))  # type: ignore[arg-type]


def test_the_request_picks_level_nodes_and_window(log: Path) -> None:
    assert len(_lines(log)) == 4
    assert _lines(log, level=msgs.Log.WARN) == [
        "[WARN] [3.000] [/follower]: waiting",
        "[ERROR] [4.000] [explorer]: stuck",
    ]
    assert [x[-4:] for x in _lines(log, nodes=("/follower",))] == ["tick", "ting"]
    assert _lines(log, since_ns=2 * S, until_ns=3 * S, level=msgs.Log.DEBUG) == [
        "[DEBUG] [2.000] [follower]: tick",
        "[WARN] [3.000] [/follower]: waiting",
    ]


def test_a_node_that_never_logged_is_named_with_those_that_did(log: Path) -> None:
    with pytest.raises(
        UsageError,
        match=r"no node camera in /rosout; the nodes that logged: "
        r"/follower, explorer, follower",
    ):
        _lines(log, nodes=("camera",))


def test_a_log_without_rosout(tmp_path: Path) -> None:
    path = tmp_path / "quiet.mcap"
    with bag.BagWriter(path) as w:
        w.add_metadata(bag.RUN_METADATA, {})
        w.write("/explorer/cmd_vel", msgs.Twist(), S)
    assert _lines(path) == []
    with pytest.raises(UsageError, match=r"no node logged anything \(no /rosout\)"):
        _lines(path, nodes=("explorer",))
