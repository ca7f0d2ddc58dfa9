"""log/info: `usar info`'s report on real logs written by usar's writer: whole, cut, crashed."""

from __future__ import annotations

from pathlib import Path

from conftest import one_room

from usar_replay.core import contract, msgs
from usar_replay.log import bag
from usar_replay.log.info import describe, is_whole, open_checked
from usar_replay.world.scenario_toml import to_toml

S = 1_000_000_000


def _log(path: Path, *, outcome: str = "done", reason: str = "", scenario: bool = True) -> Path:
    with bag.BagWriter(path, chunk_size=1024) as w:
        w.add_metadata(bag.RUN_METADATA, {"usar_version": "test"})
        if scenario:
            w.add_attachment(
                contract.SCENARIO_ATTACHMENT, "application/toml", to_toml(one_room()).encode(), S
            )
        for i in range(200):
            w.write(contract.cmd_vel("explorer"), msgs.Twist(), S + i * S // 20)
        w.close(outcome=outcome, outcome_reason=reason)
    return path


def _fields(text: str) -> dict[str, str]:
    out: dict[str, str] = {}
    for line in text.splitlines():
        if not line.startswith(" ") and ":" in line:
            key, _, value = line.partition(":")
            out.setdefault(key, value.strip())
    return out


def test_a_whole_log(tmp_path: Path) -> None:
    run = open_checked(_log(tmp_path / "a.mcap"))
    assert is_whole(run)
    text = describe(run)
    f = _fields(text)
    assert f["File state"] == "complete (closed and indexed); every CRC checked"
    assert f["Mission"] == "done (the mission finished)"
    assert f["Duration"] == "9.950 s (sim time)" and f["Messages"] == "200"
    assert f["Start"] == "1.000 s"
    assert "  /explorer/cmd_vel  geometry_msgs/msg/Twist      200" in text.splitlines()
    assert "one-room" in text and "Settings (not recorded; defaults):" in text
    assert "  usar_version = test" in text.splitlines()
    assert all(len(line) <= 100 for line in text.splitlines())
    quick = describe(open_checked(tmp_path / "a.mcap", quick=True), quick=True)
    assert "; summary trusted, data not checked" in quick


def test_a_cut_log_says_what_to_do(tmp_path: Path) -> None:
    data = _log(tmp_path / "a.mcap").read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    run = open_checked(cut)
    assert not is_whole(run)
    text = describe(run)
    f = _fields(text)
    assert f["File state"].startswith("INCOMPLETE")
    assert "Damage" in f and "What to do" in f
    flat = " ".join(text.split())  # the advice is wrapped to 100 columns
    assert f"What to do: `usar recover {cut}` writes what it holds to an indexed log" in flat
    assert all(len(line) <= 100 for line in text.splitlines())


def test_a_crash_reason_is_one_safe_line(tmp_path: Path) -> None:
    reason = "ZeroDivisionError\x1b[2J: boom\nTraceback ..."
    run = open_checked(_log(tmp_path / "a.mcap", outcome="crashed", reason=reason, scenario=False))
    text = describe(run)
    assert _fields(text)["Mission"] == "the mission's code crashed: ZeroDivisionError\\x1b[2J: boom"
    assert "  (no scenario attached)" in text.splitlines()


def test_a_label_as_wide_as_the_column_keeps_a_space_after_its_colon() -> None:
    """Issue 50, seen in passing: ``Start read from:usar.toml [ros1]``."""
    from usar_replay.log.info import _field

    assert _field("Start read from", "usar.toml [ros1]") == ["Start read from: usar.toml [ros1]"]
    assert _field("Started with", "rosrun a b") == ["Started with:  rosrun a b"]  # as before
    long = _field("Start read from", "x " * 60)
    assert long[0].startswith("Start read from: x") and all(len(ln) <= 100 for ln in long)


def test_attachments_nested_thousands_deep_are_problems_not_tracebacks(tmp_path: Path) -> None:
    """A log is anyone's file: its TOML attachments nested 5,000 deep (``tomllib`` recurses)
    are said invalid, as a malformed one is, and ``usar info`` still reports."""
    bomb = ("a = " + "[" * 5000 + "]" * 5000 + "\n").encode()
    path = tmp_path / "deep.mcap"
    with bag.BagWriter(path, chunk_size=1024) as w:
        w.add_metadata(bag.RUN_METADATA, {"usar_version": "test"})
        for name in (contract.SCENARIO_ATTACHMENT, contract.SETTINGS_ATTACHMENT,
                     contract.MISSION_ATTACHMENT, contract.ROS1_ATTACHMENT):  # fmt: skip
            w.add_attachment(name, "application/toml", bomb, S)
        w.write(contract.cmd_vel("explorer"), msgs.Twist(), S)
        w.close(outcome="done", outcome_reason="")
    text = describe(open_checked(path))
    assert f"the attached {contract.MISSION_ATTACHMENT} is invalid" in text
    assert "nested too deep" in text
