"""The mission wire protocol: frames round-trip, their bytes are pinned (the worker, the recorder
and the ROS 1 bridge must agree on them), and bytes that are not a frame are refused with one
line, never read past their end."""

from __future__ import annotations

import struct

import pytest
from hypothesis import given
from hypothesis import strategies as st

from usar_replay.core.errors import MissionEnded, ProtocolMismatch
from usar_replay.process import protocol
from usar_replay.process.protocol import FrameKind

# the frame kinds' bytes are the protocol: a change here is a new PROTOCOL_VERSION
KIND_BYTES = {
    "TICK": b"T",
    "OUTPUTS": b"O",
    "READY": b"R",
    "STOP": b"S",
    "CRASHED": b"C",
    "OUT_OF_MEMORY": b"M",
    "REFUSED": b"F",
}

_text = st.text(max_size=40)
_wire = st.tuples(_text, _text, st.binary(max_size=200))


def test_the_frame_kinds_are_pinned_and_distinct() -> None:
    assert {k.name: bytes(k) for k in FrameKind} == KIND_BYTES
    assert b"S-and-more"[:1] == FrameKind.STOP  # a frame's first byte compares as the kind
    assert FrameKind(b"C") is FrameKind.CRASHED
    assert protocol.PROTOCOL_VERSION == 1


def test_a_tick_frames_bytes_are_pinned() -> None:
    """The layout in the module doc, byte for byte."""
    frame = protocol.tick_frame(1_500_000_000, [("/odom", "nav_msgs/msg/Odometry", b"\x00\x01")])
    assert frame == (
        b"T"
        + (1_500_000_000).to_bytes(8, "little")
        + (1).to_bytes(4, "little")
        + b"\x00"
        + b"\x05\x00"
        + b"\x15\x00"
        + b"\x02\x00\x00\x00"
        + b"/odom"
        + b"nav_msgs/msg/Odometry"
        + b"\x00\x01"
    )
    assert protocol.pack(FrameKind.TICK, 1_500_000_000, []) == (
        b"T" + struct.pack("<qI", 1_500_000_000, 0) + b"\x00"
    )


def test_an_outputs_frame_carries_done_as_its_flag() -> None:
    frame = protocol.outputs_frame(-7, [], done=True)
    assert frame == b"O" + struct.pack("<qI", -7, 0) + b"\x01"
    assert protocol.unpack(frame) == (b"O", -7, [], 1)
    assert protocol.unpack(protocol.outputs_frame(3, []))[3] == 0


@given(
    kind=st.sampled_from([FrameKind.TICK, FrameKind.OUTPUTS]),
    t_ns=st.integers(-(2**63), 2**63 - 1),
    items=st.lists(_wire, max_size=6),
    flag=st.integers(0, 255),
)
def test_pack_and_unpack_round_trip(
    kind: FrameKind, t_ns: int, items: list[tuple[str, str, bytes]], flag: int
) -> None:
    frame = protocol.unpack(protocol.pack(kind, t_ns, items, flag))
    assert frame.kind == kind
    assert frame.t_ns == t_ns
    assert frame.items == items
    assert frame.flag == flag


def test_the_ready_frame_carries_the_version() -> None:
    assert protocol.ready_frame() == b"R" + struct.pack("<H", protocol.PROTOCOL_VERSION)
    assert protocol.check_ready(protocol.ready_frame()) == ""  # no error, nothing said


def test_the_ready_frame_may_say_what_the_process_configured() -> None:
    """The ROS 1 bridge's goal tolerances reach the recorder this way, not through a file the
    graph could rewrite."""
    frame = protocol.ready_frame('{"goal_tolerances": []}')
    assert frame.startswith(protocol.ready_frame() + b"I")
    assert protocol.check_ready(frame) == '{"goal_tolerances": []}'


@pytest.mark.parametrize(
    ("frame", "says"),
    [
        (b"R", "no protocol version usar knows"),  # an older usar's ready
        (b"R" + struct.pack("<H", 99), "protocol version 99"),
        (b"R\x01\x00\x00", "no protocol version usar knows"),
    ],
)
def test_a_ready_of_another_version_is_a_clear_error(frame: bytes, says: str) -> None:
    with pytest.raises(ProtocolMismatch) as err:
        protocol.check_ready(frame, "the ROS 1 bridge")
    text = err.value.detail
    assert text.startswith(f"the ROS 1 bridge speaks {says}, this usar speaks version 1")
    assert "\n" not in text and text in str(err.value)
    # a mission can forge any frame: a mismatch ends the run like any refused output
    assert isinstance(err.value, MissionEnded) and err.value.verdict == "refused"
    assert err.value.exit_code == 4


def test_text_frames_carry_the_users_text() -> None:
    frame = protocol.text_frame(FrameKind.CRASHED, "Traceback ...\nZeroDivisionError: é")
    assert frame == b"C" + "Traceback ...\nZeroDivisionError: é".encode()
    assert protocol.text_of(frame) == "Traceback ...\nZeroDivisionError: é"
    assert protocol.text_of(b"F\xff ok") == "\ufffd ok"  # not UTF-8: shown, not raised


_GOOD = protocol.tick_frame(5, [("/a", "std_msgs/msg/String", b"xyz"), ("/b", "t", b"")])


@pytest.mark.parametrize(
    ("frame", "says"),
    [
        (b"", "cut short"),
        (b"O", "cut short"),
        (_GOOD[:13], "cut short"),  # no flag byte
        (_GOOD[:20], "cut short"),  # an item header cut
        (_GOOD[:-1], "past the end"),  # the last item's data one byte short
        (_GOOD + b"\x00", "1 bytes after the last item"),
        (b"O" + struct.pack("<qI", 0, 2**32 - 1) + b"\x00", "cut short"),  # a count of 4 G
        (
            b"O" + struct.pack("<qI", 0, 1) + b"\x00" + struct.pack("<HHI", 2, 0, 0) + b"\xff\xfe",
            "not UTF-8",
        ),
    ],
)
def test_bytes_that_are_not_a_frame_are_refused_with_one_line(frame: bytes, says: str) -> None:
    with pytest.raises(ValueError) as err:
        protocol.unpack(frame)
    assert says in str(err.value)
    assert "\n" not in str(err.value)


@given(st.binary(max_size=64))
def test_garbage_is_read_or_refused_never_anything_else(data: bytes) -> None:
    """Whatever the bytes: a frame that packs back to them, or a ValueError."""
    try:
        frame = protocol.unpack(data)
    except ValueError:
        return
    assert protocol.pack(frame.kind, frame.t_ns, frame.items, frame.flag) == data
