"""core/msg_text: messages as ``ros2 topic echo`` text within a width, and checked field paths."""

from __future__ import annotations

import pytest

from usar_replay.core import msgs
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


def test_a_long_string_is_continued_and_reads_back_unchanged() -> None:
    yaml = pytest.importorskip("yaml")
    for text in ("x" * 150, "word " * 40 + "end", "tab\there " * 20 + "\x1b[2J"):
        lines = message_lines(msgs.String(data=text))
        assert len(lines) > 1 and all(len(line) <= 100 for line in lines)
        assert yaml.safe_load("\n".join(lines)) == {"data": text}


def test_field_paths_are_checked_against_the_type() -> None:
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
