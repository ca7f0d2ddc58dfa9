"""log/echo: one topic's messages as blocks, from a real log written by usar's writer."""

from __future__ import annotations

from pathlib import Path

import pytest

from usar_replay.core import msgs, ros1msg
from usar_replay.core.errors import IncompleteLog, UsageError
from usar_replay.log import bag
from usar_replay.log.echo import EchoRequest, blocks, find_topic
from usar_replay.log.run import open_run

S = 1_000_000_000
CMD = "/explorer/cmd_vel"
COUNT = ros1msg.Ros1Message(msgtype="std_msgs/Int32", definition="int32 data\n", data=b"\5\0\0\0")


@pytest.fixture(scope="module")
def log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("echo") / "run.mcap"
    with bag.BagWriter(path) as w:
        w.add_metadata(bag.RUN_METADATA, {})
        for i in range(1, 5):
            w.write(CMD, msgs.Twist(linear=msgs.Vector3(x=i / 10)), i * S, publisher="mission")
        w.write_ros1("/count", COUNT, 5 * S, publisher="mission")
    return path


def _blocks(path: Path, **kw: object) -> list[list[str]]:
    return list(blocks(open_run(path), EchoRequest(**kw)))  # type: ignore[arg-type]


def test_each_message_is_a_block_with_its_sim_time(log: Path) -> None:
    got = _blocks(log, topic=CMD)
    assert len(got) == 4
    assert got[0] == [
        "# 1.000 s", "linear:", "  x: 0.1", "  y: 0.0", "  z: 0.0",
        "angular:", "  x: 0.0", "  y: 0.0", "  z: 0.0", "---",
    ]  # fmt: skip


def test_the_window_includes_both_ends_and_fields_select(log: Path) -> None:
    got = _blocks(
        log, topic="explorer/cmd_vel", since_ns=2 * S, until_ns=3 * S, fields=("linear.x",)
    )
    assert got == [["# 2.000 s", "linear.x: 0.2", "---"], ["# 3.000 s", "linear.x: 0.3", "---"]]


def test_a_ros1_message_is_read_with_its_definition(log: Path) -> None:
    assert _blocks(log, topic="/count") == [["# 5.000 s", "data: 5", "---"]]
    with pytest.raises(UsageError, match="/count is a ROS 1 std_msgs/Int32; echo it without"):
        _blocks(log, topic="/count", fields=("data",))


def test_an_unknown_topic_or_field_is_one_error_naming_the_closest(log: Path) -> None:
    run = open_run(log)
    assert find_topic(run, "explorer/cmd_vel") == CMD
    with pytest.raises(UsageError, match=r"no topic /explorer/cmd_vl; did you mean /explorer/cmd"):
        find_topic(run, "/explorer/cmd_vl")
    with pytest.raises(UsageError, match=r"--fields linear\.w: geometry_msgs/msg/Vector3 has no"):
        _blocks(log, topic=CMD, fields=("linear.w",))


def test_in_a_damaged_log_an_unknown_topic_may_lie_past_the_damage(
    log: Path, tmp_path: Path
) -> None:
    data = log.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    run = open_run(cut)
    assert run.damage is not None
    with pytest.raises(IncompleteLog, match="in the readable part of the log"):
        find_topic(run, "/nowhere")
