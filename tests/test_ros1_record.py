"""What a ROS 1 run keeps: the package's own topics, its stored markers, each node's lines.

A two-node package (``examples/ros1/usar_two_nodes``: the explorer node publishes its stored
markers latched as a ``geometry_msgs/PoseArray`` on ``/explorer/marker_poses`` and a
``std_msgs/Int32`` count usar has no type for; the follower node waits for them) is built and
recorded on the one-room world, once for the module; then the log is read as a student would:
``usar echo``, ``usar log --node``, the summary, the report's picture.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path

import pytest
from clitools import usar
from conftest import one_room

from usar_replay.core import msgs, ros1msg
from usar_replay.grading.htmlreport import collect
from usar_replay.log.run import open_run
from usar_replay.world.scenario_toml import save

PACKAGE = Path(__file__).resolve().parents[1] / "examples" / "ros1" / "usar_two_nodes"


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Path, str]]:
    """The two-node package recorded on the one-room world: (log, what `usar record` printed)."""
    tmp = tmp_path_factory.mktemp("two_nodes")
    before = os.environ.get("XDG_CACHE_HOME")
    os.environ["XDG_CACHE_HOME"] = str(tmp / "cache")
    world = tmp / "room.toml"
    save(one_room(), world)
    out = tmp / "two.mcap"
    try:
        done = usar("record", "--scenario", str(world), "--ros1", str(PACKAGE), "--out", str(out))
    finally:
        if before is None:
            del os.environ["XDG_CACHE_HOME"]
        else:
            os.environ["XDG_CACHE_HOME"] = before
    assert done.returncode == 0, done.stdout + done.stderr
    yield out, done.stdout + done.stderr


def test_the_package_topics_are_in_the_log(recorded: tuple[Path, str]) -> None:
    out, _ = recorded
    run = open_run(out)
    assert run.outcome == "done", run.outcome_reason
    topics = run.topics
    assert topics["/explorer/marker_poses"].msgtype == "geometry_msgs/msg/PoseArray"
    # a type usar has no value for stays in its ROS 1 encoding, with its definition
    assert topics["/explorer/stored_count"].msgtype == "std_msgs/Int32"
    assert run.reader.ros1_definition("/explorer/stored_count") == (
        "std_msgs/Int32",
        "int32 data\n",
    )
    poses = [m.msg for m in run.messages(["/explorer/marker_poses"])]
    assert len(poses) == 1 and isinstance(poses[0], msgs.PoseArray)
    assert len(poses[0].poses) == 1
    # usar's own topics are not recorded twice (the bridge's move_base action topics)
    assert not [t for t in topics if "/move_base/" in t]


def test_echo_reads_both_encodings(recorded: tuple[Path, str]) -> None:
    out, _ = recorded
    poses = usar("echo", str(out), "/explorer/marker_poses")
    assert poses.returncode == 0, poses.stderr
    assert "poses:\n- position:\n    x: 1.9" in poses.stdout
    count = usar("echo", str(out), "explorer/stored_count")
    assert count.returncode == 0, count.stderr
    assert count.stdout.splitlines()[1:] == ["data: 1", "---"]


def test_a_ros1_message_decodes_only_as_its_definition() -> None:
    value = ros1msg.Ros1Message(
        msgtype="std_msgs/Int32", definition="int32 data\n", data=b"\x07\0\0\0"
    )
    wire_type, data = ros1msg.pack(value)
    assert ros1msg.unpack(wire_type, data) == value
    assert ros1msg.decode(value.msgtype, value.definition, value.data).data == 7
    with pytest.raises(Exception, match="size mismatch"):
        ros1msg.decode(value.msgtype, value.definition, value.data + b"\0")


def test_the_stored_markers_are_shown(recorded: tuple[Path, str]) -> None:
    out, printed = recorded
    assert "stored on /explorer/marker_poses at (1.99" in printed
    pic = collect(open_run(out))
    assert list(pic.stored) == [0] and pic.stored_on == "/explorer/marker_poses"


def test_log_by_node_finds_each_node(recorded: tuple[Path, str]) -> None:
    out, _ = recorded
    for name in ("explorer", "/explorer"):
        got = usar("log", str(out), "--node", name)
        assert got.returncode == 0, got.stderr
        assert "[explorer]: explorer: home" in got.stdout
        assert "[follower]" not in got.stdout
    follower = usar("log", str(out), "--node", "follower").stdout
    assert "waiting for the explorer's markers" in follower


def test_a_repeated_line_does_not_take_the_status_line() -> None:
    from usar_replay.pipeline.status_line import NodeLines

    lines = NodeLines()
    lines.note(msgs.Log(name="follower", msg="follower: waiting"))
    lines.note(msgs.Log(name="/explorer", msg="explorer: at target_1"))
    lines.note(msgs.Log(name="follower", msg="follower: waiting"))
    assert lines.status() == "[explorer] explorer: at target_1"
    lines.note(msgs.Log(name="follower", msg="follower: to marker 0"))
    assert lines.status() == "[follower] follower: to marker 0"
