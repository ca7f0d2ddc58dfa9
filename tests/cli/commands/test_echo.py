"""`usar echo`: a log's messages, as ROS 2 prints them (`usar log`: tests/cli/commands/test_log.py).

Why: a student reading their mission's own log lines, or the command a robot was sent at the
time a grade line names, must not need the mcap library. The blocks follow ``ros2 topic echo``
(nested fields indented, message lists as ``- `` items, ``---`` after each), every line fits
100 columns, image bytes never flood the terminal, and the times are the clock of ``usar
grade``'s 'at' column. Run on the one-room recording of conftest (real MCAP, real messages).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from tests.clitools import one_error_line, usar
from usar_replay.cli.main import main
from usar_replay.core import msgs
from usar_replay.log import bag
from usar_replay.pipeline.record import RecordResult

Room = tuple[Path, RecordResult]
IMAGE = "/explorer/camera/rgb/image_raw/compressed"


def _echo(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, list[str]]:
    """``usar ARGS`` in this process: its exit code and stdout's lines."""
    code = main(list(args))
    return code, capsys.readouterr().out.splitlines()


def _blocks(lines: list[str]) -> list[list[str]]:
    """The output cut into message blocks (each ends with ``---``)."""
    out: list[list[str]] = [[]]
    for line in lines:
        out[-1].append(line)
        if line == "---":
            out.append([])
    assert out[-1] == [], "the output must end with ---"
    return out[:-1]


def _first(path: Path, topic: str, after_ns: int = 0) -> tuple[int, msgs.Message]:
    for m in bag.BagReader(path).messages([topic]):
        if m.log_time_ns >= after_ns and m.msg is not None:
            return m.log_time_ns, m.msg
    raise AssertionError(f"no {topic} in the log")


def _t(ns: int) -> str:
    return f"{ns / 1e9:.3f}"


# -- usar echo ---------------------------------------------------------------------------------


def test_a_twist_is_one_block_like_ros2_topic_echo(
    room_log: Room, capsys: pytest.CaptureFixture[str]
) -> None:
    t, m = _first(room_log[0], "/explorer/cmd_vel", after_ns=5_000_000_000)
    assert isinstance(m, msgs.Twist)
    code, lines = _echo(capsys, "echo", str(room_log[0]), "/explorer/cmd_vel",
                        "--since", _t(t), "--until", _t(t))  # fmt: skip
    assert code == 0
    first = _blocks(lines)[0]
    assert first == [
        f"# {_t(t)} s",
        "linear:",
        f"  x: {m.linear.x!r}",
        f"  y: {m.linear.y!r}",
        f"  z: {m.linear.z!r}",
        "angular:",
        f"  x: {m.angular.x!r}",
        f"  y: {m.angular.y!r}",
        f"  z: {m.angular.z!r}",
        "---",
    ]


def test_a_tf_message_lists_its_transforms_as_items(
    room_log: Room, capsys: pytest.CaptureFixture[str]
) -> None:
    t, m = _first(room_log[0], "/tf_static")
    assert isinstance(m, msgs.TFMessage) and len(m.transforms) > 1
    code, lines = _echo(capsys, "echo", str(room_log[0]), "tf_static")  # the / is optional
    assert code == 0
    (block,) = _blocks(lines)
    assert block[:2] == [f"# {_t(t)} s", "transforms:"]
    assert block.count("- header:") == len(m.transforms)
    tf = m.transforms[0]
    assert block[2:9] == [
        "- header:",
        "    stamp:",
        f"      sec: {tf.header.stamp.sec}",
        f"      nanosec: {tf.header.stamp.nanosec}",
        f"    frame_id: {tf.header.frame_id}",
        f"  child_frame_id: {tf.child_frame_id}",
        "  transform:",
    ]
    children = [line.split(": ")[1] for line in block if line.startswith("  child_frame_id:")]
    assert children == [x.child_frame_id for x in m.transforms]


def test_fields_selects_dotted_paths_and_list_items(
    room_log: Room, capsys: pytest.CaptureFixture[str]
) -> None:
    log = str(room_log[0])
    code, lines = _echo(capsys, "echo", log, "/explorer/cmd_vel", "--fields", "linear.x,angular.z")
    assert code == 0
    reader = bag.BagReader(room_log[0])
    sent = [m.msg for m in reader.messages(["/explorer/cmd_vel"])]
    blocks = _blocks(lines)
    assert len(blocks) == len(sent)
    for block, m in zip(blocks, sent, strict=True):
        assert isinstance(m, msgs.Twist)
        assert block[1:] == [f"linear.x: {m.linear.x!r}", f"angular.z: {m.angular.z!r}", "---"]
    _, lines = _echo(capsys, "echo", log, "/tf_static", "--fields", "transforms.1.child_frame_id")
    _, tf = _first(room_log[0], "/tf_static")
    assert isinstance(tf, msgs.TFMessage)
    assert lines[1] == f"transforms.1.child_frame_id: {tf.transforms[1].child_frame_id}"


def test_since_and_until_are_the_grade_clock_both_included(
    room_log: Room, capsys: pytest.CaptureFixture[str]
) -> None:
    reader = bag.BagReader(room_log[0])
    assert reader.start_ns == 1_000_000_000  # the sim clock starts at 1 s: no offset to apply
    times = [m.log_time_ns for m in reader.messages(["/explorer/odom"])]
    since, until = times[10], times[20]
    code, lines = _echo(capsys, "echo", str(room_log[0]), "/explorer/odom",
                        "--since", _t(since), "--until", _t(until))  # fmt: skip
    assert code == 0
    shown = [line for line in lines if line.startswith("# ")]
    assert shown == [f"# {_t(t)} s" for t in times if since <= t <= until]
    assert shown[0] == f"# {_t(since)} s" and shown[-1] == f"# {_t(until)} s"


def test_every_line_of_every_topic_fits_100_columns(
    room_log: Room, capsys: pytest.CaptureFixture[str]
) -> None:
    reader = bag.BagReader(room_log[0])
    for topic in reader.topics:
        code, lines = _echo(capsys, "echo", str(room_log[0]), topic)
        assert code == 0 and lines, topic
        long = [line for line in lines if len(line) > 100]
        assert not long, f"{topic}: {long[0]}"


def test_image_bytes_are_a_size_unless_full_length(
    room_log: Room, capsys: pytest.CaptureFixture[str]
) -> None:
    t, m = _first(room_log[0], IMAGE)
    assert isinstance(m, msgs.CompressedImage) and len(m.data) > 1000
    log = str(room_log[0])
    code, lines = _echo(capsys, "echo", log, IMAGE, "--until", _t(t))
    assert code == 0
    assert f"data: <{len(m.data):,} bytes>" in lines
    assert max(map(len, lines)) <= 100
    code, lines = _echo(capsys, "echo", log, IMAGE, "--until", _t(t), "--fields", "data",
                        "--full-length")  # fmt: skip
    assert code == 0 and lines[1].startswith("data: [")
    assert max(map(len, lines)) <= 100
    numbers = " ".join(lines[1:-1]).removeprefix("data: [").removesuffix("]").split(", ")
    assert bytes(int(n) for n in numbers) == m.data


def test_an_unknown_topic_names_the_closest_topics(room_log: Room) -> None:
    out = usar("echo", str(room_log[0]), "/explorer/cmdvel")
    one_error_line(out, 2, "no topic /explorer/cmdvel", "did you mean /explorer/cmd_vel?")
    assert "`usar info` lists all" in out.stderr
    # the line fits 100 columns but for the log's own path, which the user chose
    assert len(out.stderr.rstrip()) - len(str(room_log[0])) <= 100
    assert out.stdout == ""


def test_a_bad_field_names_the_fields_there_are(room_log: Room) -> None:
    out = usar("echo", str(room_log[0]), "/explorer/cmd_vel", "--fields", "linear.q")
    one_error_line(out, 2, "--fields linear.q", "geometry_msgs/msg/Vector3", "x, y, z")
    out = usar("echo", str(room_log[0]), "/tf", "--fields", "transforms.child_frame_id")
    one_error_line(out, 2, "transforms is a list", "transforms.0")
    out = usar("echo", str(room_log[0]), "/tf", "--since", "5", "--until", "4")
    one_error_line(out, 2, "--until 4.0 is before --since 5.0")


def test_a_damaged_log_is_echoed_as_far_as_it_goes(room_log: Room, tmp_path: Path) -> None:
    data = room_log[0].read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    out = usar("echo", str(cut), "/explorer/cmd_vel", "--fields", "linear.x")
    assert out.returncode == 3 and "Traceback" not in out.stderr
    assert out.stdout.count("---") > 10
    (note,) = out.stderr.strip().splitlines()
    assert "the log is incomplete" in note and "echoed as far as it goes" in note


def test_a_closed_pipe_ends_quietly(room_log: Room) -> None:
    """``usar echo LOG /tf | head``: no traceback, no ``Exception ignored``, exit 0."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "usar_replay.cli", "echo", str(room_log[0]), "/tf"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    assert proc.stdout is not None and proc.stderr is not None
    assert proc.stdout.read(200).startswith(b"# 1.000 s\n")
    proc.stdout.close()  # the reader goes away with most of the output unread
    err = proc.stderr.read().decode()
    assert proc.wait() == 0 and err == ""
