"""`usar echo` and `usar log`: a log's messages and its /rosout lines, as ROS 2 prints them.

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
from tests.logtools import rewrite
from usar_replay.cli.main import main
from usar_replay.core import msg_text, msgs
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


# -- usar log ----------------------------------------------------------------------------------


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


# -- the printer -------------------------------------------------------------------------------


def _read_double_quoted(lines: list[str]) -> str:
    """A YAML double-quoted scalar continued with ``\\`` (what the printer writes), read back
    by YAML's rules: an escaped line break and the next line's indent are dropped."""
    text = lines[0].split(': "', 1)[1]
    for line in lines[1:]:
        assert text.endswith("\\")
        text = text[:-1] + line.lstrip(" ")
    assert text.endswith('"')
    escapes = {"n": "\n", "t": "\t", "\\": "\\", '"': '"', " ": " "}
    out, i = [], 0
    body = text[:-1]
    while i < len(body):
        if body[i] == "\\":
            out.append(escapes[body[i + 1]])
            i += 2
        else:
            out.append(body[i])
            i += 1
    return "".join(out)


@pytest.mark.parametrize(
    "text",
    [
        "a long line of words, " * 9,
        "x" * 250,
        'quotes " and \\ backslashes,  double  spaces ' * 4 + "\nand\ta traceback's lines",
    ],
)
def test_a_long_string_is_continued_and_reads_back_unchanged(text: str) -> None:
    lines = msg_text.message_lines(msgs.Log(name="n", msg=text))
    start = next(i for i, line in enumerate(lines) if line.startswith('msg: "'))
    end = next(i for i in range(start, len(lines)) if lines[i].endswith('"'))
    assert max(map(len, lines)) <= 100
    assert _read_double_quoted(lines[start : end + 1]) == text


def test_a_long_array_is_elided_with_its_count() -> None:
    info = msgs.CameraInfo(d=tuple(float(i) for i in range(1000)))
    lines = msg_text.message_lines(info)
    d = next(line for line in lines if line.startswith("d: "))
    assert d.startswith("d: [0.0, 1.0, 2.0,")
    assert any(line.endswith(f"... {1000 - msg_text.MAX_ITEMS} more]") for line in lines)
    assert max(map(len, lines)) <= 100
    assert len(msg_text.message_lines(info, full=True)) > len(lines)


def test_a_field_path_is_checked_against_the_type() -> None:
    path = msg_text.field_path(msgs.Odometry, "pose.pose.position.x")
    odom = msgs.Odometry(pose=msgs.PoseWithCovariance(pose=msgs.Pose(position=msgs.Point(x=1.5))))
    assert msg_text.path_lines(path, odom) == ["pose.pose.position.x: 1.5"]
    with pytest.raises(msg_text.FieldPathError, match="its fields: pose, covariance"):
        msg_text.field_path(msgs.Odometry, "pose.position")
    with pytest.raises(msg_text.FieldPathError, match="single value"):
        msg_text.field_path(msgs.Odometry, "child_frame_id.x")
