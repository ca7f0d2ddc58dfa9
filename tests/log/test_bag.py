"""The log: MCAP writing and reading, proven against independent readers (rosbags, mcap)."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mcap.reader import make_reader
from msg_strategies import message
from rosbags.highlevel import AnyReader

from usar_replay.core import msgs
from usar_replay.core.errors import NotAnMcapFile, UsageError
from usar_replay.log import bag

T0 = 1_000_000_000


def _plain(value: Any) -> Any:
    """A comparable plain-Python form of our values and of rosbags' values."""
    if isinstance(value, msgs.Message):
        return {f.name: _plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if hasattr(value, "__msgtype__") and dataclasses.is_dataclass(value):
        return {
            f.name: _plain(getattr(value, f.name))
            for f in dataclasses.fields(value)
            if f.name != "__msgtype__" and not f.name.isupper()  # constants, e.g. Log.INFO
        }
    if isinstance(value, bytes):
        return list(value)
    if isinstance(value, np.ndarray):
        if value.dtype == np.int8:  # int8[] (OccupancyGrid.data) is carried as raw bytes
            value = value.view(np.uint8)
        return [_plain(v) for v in value.tolist()]
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


def _write_all_types(path: Path, values: dict[str, msgs.Message]) -> None:
    with bag.BagWriter(path) as w:
        for i, (topic, value) in enumerate(values.items()):
            w.write(topic, value, T0 + i)


@settings(
    max_examples=5, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(st.fixed_dictionaries({f"/t{i}": message(cls) for i, cls in enumerate(msgs.MESSAGE_TYPES)}))
def test_rosbags_reads_every_type_to_the_same_values(
    tmp_path: Path, values: dict[str, msgs.Message]
) -> None:
    """rosbags' own reader and typestore (not our code) decode every message identically."""
    path = tmp_path / "all.mcap"
    _write_all_types(path, values)
    seen = {}
    with AnyReader([path]) as reader:
        for conn, t, raw in reader.messages():
            assert conn.msgtype == values[conn.topic].__msgtype__
            seen[conn.topic] = (t, reader.deserialize(raw, conn.msgtype))
    assert set(seen) == set(values)
    for i, (topic, value) in enumerate(values.items()):
        t, ros = seen[topic]
        assert t == T0 + i
        assert _plain(ros) == _plain(value), topic


@settings(
    max_examples=15, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(st.lists(st.sampled_from(msgs.MESSAGE_TYPES).flatmap(message), min_size=1, max_size=6))
def test_write_read_round_trip(tmp_path: Path, values: list[msgs.Message]) -> None:
    path = tmp_path / "rt.mcap"
    with bag.BagWriter(path) as w:
        for i, v in enumerate(values):
            w.write(f"/topic_{type(v).__name__}", v, T0 + i * 1000)
    got = [m.msg for m in bag.BagReader(path).messages()]
    assert got == values


def _sample(path: Path, n: int = 300, chunk_size: int = 4096) -> None:
    with bag.BagWriter(path, chunk_size=chunk_size) as w:
        w.add_attachment("scenario.toml", "application/toml", b'name = "x"\n', T0)
        w.add_metadata(bag.RUN_METADATA, {"seed": "7"})
        w.write("/tf_static", msgs.TFMessage(), T0)
        for i in range(n):
            t = T0 + i * 100_000_000
            stamp = msgs.Time.from_ns(t)
            w.write("/explorer/cmd_vel", msgs.Twist(linear=msgs.Vector3(x=i * 0.001)), t)
            w.write(
                "/explorer/camera/rgb/image_raw/compressed",
                msgs.CompressedImage(
                    header=msgs.Header(stamp=stamp, frame_id="cam"),
                    format="png",
                    data=bytes(range(256)) * 4,
                ),
                t,
            )


def test_file_follows_the_ros2_profile(tmp_path: Path) -> None:
    path = tmp_path / "p.mcap"
    _sample(path, n=20)
    with open(path, "rb") as f:
        reader = make_reader(f)
        header = reader.get_header()
        summary = reader.get_summary()
        assert header.profile == "ros2"
        assert summary is not None and summary.statistics is not None
        assert summary.chunk_indexes, "messages are written in chunks"
        assert {c.compression for c in summary.chunk_indexes} == {"zstd"}
        for schema in summary.schemas.values():
            assert schema.encoding == "ros2msg"
            assert schema.name.count("/msg/") == 1
        for channel in summary.channels.values():
            assert channel.message_encoding == "cdr"
            qos = channel.metadata["offered_qos_profiles"]
            durability = "durability: 1" if channel.topic == "/tf_static" else "durability: 2"
            assert durability in qos
        for _, _, m in reader.iter_messages():
            assert m.log_time == m.publish_time
        assert [a.name for a in reader.iter_attachments()] == ["scenario.toml"]
        names = {m.name: m.metadata for m in reader.iter_metadata()}
        assert names[bag.STATUS_METADATA]["status"] == "complete"
        assert names[bag.RUN_METADATA] == {"seed": "7"}


def test_reader_summary_filters_and_order(tmp_path: Path) -> None:
    path = tmp_path / "s.mcap"
    _sample(path, n=50)
    r = bag.BagReader(path)
    assert r.complete and r.status == "complete" and r.damage is None
    assert r.topics["/explorer/cmd_vel"].count == 50
    assert r.topics["/explorer/cmd_vel"].msgtype == "geometry_msgs/msg/Twist"
    assert r.start_ns == T0 and r.end_ns == T0 + 49 * 100_000_000
    assert r.attachments["scenario.toml"] == b'name = "x"\n'
    times = [m.log_time_ns for m in r.messages()]
    assert times == sorted(times) and len(times) == 101
    window = list(r.messages(["/explorer/cmd_vel"], T0 + 1_000_000_000, T0 + 2_000_000_000))
    assert [m.log_time_ns for m in window] == [T0 + k * 100_000_000 for k in range(10, 20)]
    assert all(isinstance(m.msg, msgs.Twist) for m in window)
    raw = next(r.messages(["/explorer/cmd_vel"], decode_messages=False))
    assert raw.msg is None and bag.decode(raw.data, raw.msgtype) == msgs.Twist()


def test_decoded_gives_what_messages_gives(tmp_path: Path) -> None:
    """The grader's lean stream: the same values, times and order as :meth:`messages`."""
    path = tmp_path / "d.mcap"
    _sample(path, n=120, chunk_size=4096)
    r = bag.BagReader(path)
    topics = ["/explorer/cmd_vel", "/tf_static"]
    want = [(m.topic, m.msg, m.log_time_ns) for m in r.messages(topics)]
    assert len(want) == 121 and isinstance(want[-1][1], msgs.Twist)
    assert list(bag.BagReader(path).decoded(topics)) == want


def test_decoded_skips_a_damaged_chunk_as_messages_does(tmp_path: Path) -> None:
    path = tmp_path / "d.mcap"
    _sample(path, n=300, chunk_size=4096)
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0xFF  # inside some chunk: its CRC (or zstd) fails
    path.write_bytes(bytes(data))
    topics = ["/explorer/cmd_vel"]
    a, b = bag.BagReader(path), bag.BagReader(path)
    want = [(m.topic, m.msg, m.log_time_ns) for m in a.messages(topics)]
    assert 0 < len(want) < 300, "a chunk of commands was skipped"
    assert list(b.decoded(topics)) == want
    assert a.damage is not None and b.damage is not None
    assert b.damage.describe() == a.damage.describe()


def test_part_file_until_close(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    w = bag.BagWriter(path)
    w.write("/a", msgs.String(data="x"), T0)
    assert not path.exists() and (tmp_path / "run.mcap.part").exists()
    w.close()
    assert path.exists() and not (tmp_path / "run.mcap.part").exists()


def test_ctrl_c_leaves_a_closed_interrupted_file(tmp_path: Path) -> None:
    path = tmp_path / "int.mcap"
    with pytest.raises(KeyboardInterrupt), bag.BagWriter(path) as w:
        w.write("/a", msgs.String(data="x"), T0)
        w.write("/a", msgs.String(data="y"), T0 + 5)
        raise KeyboardInterrupt
    r = bag.BagReader(path)
    assert r.has_summary and r.status == "interrupted" and not r.complete
    assert [m.msg for m in r.messages()] == [msgs.String(data="x"), msgs.String(data="y")]


def test_log_time_may_not_go_backwards(tmp_path: Path) -> None:
    with bag.BagWriter(tmp_path / "b.mcap") as w:
        w.write("/a", msgs.String(), T0 + 10)
        with pytest.raises(ValueError, match="backwards"):
            w.write("/b", msgs.String(), T0)


@pytest.mark.parametrize("fraction", [0.3, 0.6, 0.95])
def test_truncated_file_reads_up_to_the_damage(tmp_path: Path, fraction: float) -> None:
    path = tmp_path / "full.mcap"
    _sample(path, n=300, chunk_size=4096)
    full = [(m.topic, m.log_time_ns, m.data) for m in bag.BagReader(path).messages()]
    data = path.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: int(len(data) * fraction)])
    r = bag.BagReader(cut)
    assert not r.complete and r.status == "truncated"
    assert r.damage is not None
    got = [(m.topic, m.log_time_ns, m.data) for m in r.messages()]
    assert 0 < len(got) <= len(full)
    if fraction < 0.9:
        assert len(got) < len(full)
    assert got == full[: len(got)], "what is read is an intact prefix"
    assert r.damage.messages_read == len(got)
    assert r.damage.last_time_ns == got[-1][1]
    assert f"read {len(got)} messages" in r.damage.describe()


def test_reading_streams_chunk_by_chunk(tmp_path: Path) -> None:
    """Memory does not grow with the file: the reader keeps at most a chunk's messages."""
    path = tmp_path / "big.mcap"
    _sample(path, n=2000, chunk_size=8192)
    r = bag.BagReader(path)
    it = r.messages()
    first = next(it)
    # a generator that has read one message has not decoded the rest of the file
    assert first.log_time_ns == T0
    frame = it.gi_frame  # type: ignore[attr-defined]
    assert frame is not None
    it.close()


@pytest.mark.parametrize(
    ("content", "expected", "error"),
    [
        (None, "no such file", UsageError),  # a wrong path is a usage error (2), not a bad log
        (b"", "empty", NotAnMcapFile),
        (b"hello, not mcap at all", "not an MCAP file", NotAnMcapFile),
    ],
)
def test_bad_paths_raise_one_line_errors(
    tmp_path: Path, content: bytes | None, expected: str, error: type[Exception]
) -> None:
    path = tmp_path / "x.mcap"
    if content is not None:
        path.write_bytes(content)
    with pytest.raises(error, match=expected) as info:
        bag.BagReader(path)
    assert "\n" not in str(info.value)
