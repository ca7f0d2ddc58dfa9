"""Camera frames in chunks of their own: the layout, read by mcap (CRCs on) and by rosbags."""

from __future__ import annotations

import itertools
from pathlib import Path

import pytest
from mcap.reader import SeekingReader
from mcap.records import Channel, Chunk, Message, Schema
from mcap.stream_reader import StreamReader, breakup_chunk
from rosbags.highlevel import AnyReader

from usar_replay import bag, msgs
from usar_replay.contract import IMAGE

T0 = 1_000_000_000
STEP = 50_000_000
TICKS = 60


def _tf(t: int) -> msgs.TFMessage:
    tr = msgs.TransformStamped(
        header=msgs.Header(stamp=msgs.Time.from_ns(t), frame_id="a"),
        child_frame_id="b",
        transform=msgs.Transform(translation=msgs.Vector3(x=t / 1e9)),
    )
    return msgs.TFMessage(transforms=(tr,))


def _image(t: int) -> msgs.CompressedImage:
    payload = bytes((t // STEP + i) % 251 for i in range(3000))
    return msgs.CompressedImage(
        header=msgs.Header(stamp=msgs.Time.from_ns(t), frame_id="cam"), format="jpeg", data=payload
    )


def _write(path: Path, *, image_chunks: bool) -> list[tuple[str, int]]:
    """A tick loop like the recorder's (an image every other tick, written last in its tick)."""
    order = []
    with bag.BagWriter(path, chunk_size=8_000, image_chunks=image_chunks) as w:
        for k in range(TICKS):
            t = T0 + k * STEP
            w.write("/tf", _tf(t), t)
            w.write("/odom_like", _tf(t), t)
            order += [("/tf", t), ("/odom_like", t)]
            if k % 2 == 0:
                w.write(IMAGE, _image(t), t)
                order.append((IMAGE, t))
    return order


@pytest.fixture
def paired(tmp_path: Path) -> tuple[Path, list[tuple[str, int]]]:
    path = tmp_path / "paired.mcap"
    return path, _write(path, image_chunks=True)


def test_every_chunk_holds_images_only_or_no_image(paired: tuple[Path, list]) -> None:
    path, _ = paired
    with open(path, "rb") as f:
        summary = SeekingReader(f).get_summary()
    assert summary is not None
    image_ids = {cid for cid, ch in summary.channels.items() if ch.topic == IMAGE}
    kinds = [bool(set(ci.message_index_offsets) & image_ids) for ci in summary.chunk_indexes]
    for ci, has_image in zip(summary.chunk_indexes, kinds, strict=True):
        assert set(ci.message_index_offsets) <= image_ids or not has_image
    assert kinds.count(True) >= 2 and kinds.count(False) >= 2  # several pairs were written
    # pairs: each pair covers its own time window, so windows of one kind never overlap
    for kind in (True, False):
        spans = [
            (ci.message_start_time, ci.message_end_time)
            for ci, k in zip(summary.chunk_indexes, kinds, strict=True)
            if k is kind
        ]
        assert all(a[1] < b[0] for a, b in itertools.pairwise(spans))


def test_mcap_reads_everything_with_crcs_in_the_documented_order(
    paired: tuple[Path, list],
) -> None:
    path, written = paired
    with open(path, "rb") as f:
        got = [
            (ch.topic, m.log_time)
            for _, ch, m in SeekingReader(f, validate_crcs=True).iter_messages(log_time_order=True)
        ]
    # per log time: that time's other messages in written order, then its image
    assert got == sorted(written, key=lambda tm: (tm[1], tm[0] == IMAGE))
    assert sorted(got) == sorted(written)


def test_a_reader_of_other_topics_never_opens_an_image_chunk(paired: tuple[Path, list]) -> None:
    """Corrupt every image chunk's compressed data: a CRC-checking read of /tf still works."""
    path, written = paired
    with open(path, "rb") as f:
        summary = SeekingReader(f).get_summary()
    assert summary is not None
    image_ids = {cid for cid, ch in summary.channels.items() if ch.topic == IMAGE}
    raw = bytearray(path.read_bytes())
    spoiled = 0
    for ci in summary.chunk_indexes:
        if set(ci.message_index_offsets) <= image_ids:
            body_end = ci.chunk_start_offset + ci.chunk_length
            start = body_end - ci.compressed_size
            raw[start:body_end] = bytes(ci.compressed_size)  # zeros: not zstd, CRC wrong
            spoiled += 1
    assert spoiled >= 2
    path.write_bytes(bytes(raw))
    with open(path, "rb") as f:
        reader = SeekingReader(f, validate_crcs=True)
        tf = [m.log_time for _, _, m in reader.iter_messages(topics=["/tf"])]
        assert tf == [t for topic, t in written if topic == "/tf"]
        with pytest.raises(Exception):  # noqa: B017 - the image chunks really are broken
            list(reader.iter_messages(topics=[IMAGE]))
    # and through our reader
    reader2 = bag.BagReader(path)
    assert [m.log_time_ns for m in reader2.messages(["/tf"])] == tf
    assert reader2.damage is None


def test_rosbags_reads_the_paired_layout(paired: tuple[Path, list]) -> None:
    path, written = paired
    with AnyReader([path]) as reader:
        got = sorted((conn.topic, t) for conn, t, _ in reader.messages())
        images = [
            reader.deserialize(raw, conn.msgtype)
            for conn, _, raw in reader.messages()
            if conn.topic == IMAGE
        ]
    assert got == sorted(written)
    assert bytes(images[3].data) == _image(T0 + 6 * STEP).data


def test_stream_reading_without_a_summary_finds_every_channel(paired: tuple[Path, list]) -> None:
    """Each chunk carries the schema and channel records its messages need, before them."""
    path, written = paired

    channels, schemas, seen = set(), set(), []
    with open(path, "rb") as f:
        for rec in StreamReader(f, skip_magic=False).records:  # type: ignore[arg-type]
            for r in breakup_chunk(rec) if isinstance(rec, Chunk) else (rec,):
                if isinstance(r, Schema):
                    schemas.add(r.id)
                elif isinstance(r, Channel):
                    assert r.schema_id in schemas
                    channels.add(r.id)
                elif isinstance(r, Message):
                    assert r.channel_id in channels
                    seen.append(r.log_time)
    assert sorted(seen) == sorted(t for _, t in written)


def test_default_layout_is_unchanged_file_order(tmp_path: Path) -> None:
    path = tmp_path / "plain.mcap"
    written = _write(path, image_chunks=False)
    reader = bag.BagReader(path)
    assert [(m.topic, m.log_time_ns) for m in reader.messages(decode_messages=False)] == written
