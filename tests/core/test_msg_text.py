"""core/msg_text: messages as ``ros2 topic echo`` text within a width, and checked field paths."""

from __future__ import annotations

import pytest

from usar_replay.core import msg_text, msgs
from usar_replay.core.msg_text import (
    MAX_ITEMS,
    FieldPathError,
    field_path,
    message_lines,
    path_lines,
)

TWIST = msgs.Twist(linear=msgs.Vector3(x=0.2), angular=msgs.Vector3(z=-1.0))
TF = msgs.TFMessage(transforms=(msgs.TransformStamped(child_frame_id="marker_frame"),))


def test_nested_fields_are_indented_by_two_and_lists_are_items() -> None:
    assert message_lines(TWIST) == [
        "linear:", "  x: 0.2", "  y: 0.0", "  z: 0.0",
        "angular:", "  x: 0.0", "  y: 0.0", "  z: -1.0",
    ]  # fmt: skip
    lines = message_lines(TF)
    assert lines[:3] == ["transforms:", "- header:", "    stamp:"]
    assert "    frame_id: ''" in lines and "  child_frame_id: marker_frame" in lines


def test_bytes_are_counted_not_printed() -> None:
    image = msgs.CompressedImage(format="png", data=b"\0" * 6512)
    assert message_lines(image)[-2:] == ["format: png", "data: <6,512 bytes>"]
    full = message_lines(image, full=True)  # every byte, as numbers, wrapped to the width
    assert max(map(len, full)) <= 100
    assert "".join(full[6:]).replace(" ", "") == "data:[" + ",".join(["0"] * 6512) + "]"


def test_number_arrays_are_wrapped_to_the_width_and_elided_past_max_items() -> None:
    cov = msgs.PoseWithCovariance(covariance=tuple(float(i) for i in range(36)))
    lines = message_lines(cov, width=60)
    flow = lines[lines.index(next(x for x in lines if x.startswith("covariance:"))) :]
    assert all(len(line) <= 60 for line in lines)
    assert flow[0].startswith("covariance: [0.0, 1.0,") and flow[-1].endswith("35.0]")
    assert all(line.startswith("  ") for line in flow[1:])
    info = msgs.CameraInfo(d=(0.5,) * (MAX_ITEMS + 36))
    text = "\n".join(message_lines(info))
    assert "... 36 more]" in text and text.count("0.5") == MAX_ITEMS
    assert "\n".join(message_lines(info, full=True)).count("0.5") == MAX_ITEMS + 36


def test_strings_are_quoted_where_yaml_would_misread_them() -> None:
    assert message_lines(msgs.String(data="plain words")) == ["data: plain words"]
    assert message_lines(msgs.String(data="true")) == ["data: 'true'"]
    assert message_lines(msgs.String(data="")) == ["data: ''"]
    assert message_lines(msgs.String(data="a\x1bb")) == ['data: "a\\x1bb"']


def test_field_paths_through_lists_and_past_their_end() -> None:
    path = field_path(msgs.TFMessage, "transforms.0.child_frame_id")
    assert path.parts == ("transforms", 0, "child_frame_id") and path.kind == "str"
    assert path.get(TF) == "marker_frame"
    assert path_lines(path, TF) == ["transforms.0.child_frame_id: marker_frame"]
    past = field_path(msgs.TFMessage, "transforms.3.child_frame_id")
    assert past.get(TF) is None and path_lines(past, TF) == ["transforms.3.child_frame_id: null"]
    assert path_lines(field_path(msgs.Twist, "linear"), TWIST) == [
        "linear:", "  x: 0.2", "  y: 0.0", "  z: 0.0",
    ]  # fmt: skip
    assert field_path(msgs.Twist, "angular").element is msgs.Vector3


@pytest.mark.parametrize(
    ("cls", "text", "why"),
    [
        (msgs.Twist, "linear.w", "geometry_msgs/msg/Vector3 has no field 'w'; its fields: x, y, z"),
        (msgs.TFMessage, "transforms.header", "transforms is a list; follow it with an item's"),
        (msgs.Twist, "linear.x.y", "linear.x is a single value (float); it has no field 'y'"),
    ],
)
def test_a_wrong_path_says_what_is_there(cls: type[msgs.Message], text: str, why: str) -> None:
    with pytest.raises(FieldPathError) as caught:
        field_path(cls, text)
    assert str(caught.value).startswith(why)


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
