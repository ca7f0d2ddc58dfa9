"""log/mcapfile: the MCAP file's records walked and checked, on real logs written by usar's
writer, whole, with a flipped byte, cut short, or with a broken header."""

from __future__ import annotations

from pathlib import Path

import pytest

from usar_replay.core import contract, msgs
from usar_replay.log import bag, mcapfile

S = 1_000_000_000
CMD, ODOM = contract.cmd_vel("explorer"), contract.odom("explorer")


@pytest.fixture(scope="module")
def log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("mcap") / "run.mcap"
    with bag.BagWriter(path, chunk_size=2048, compression="none") as w:
        w.add_metadata(bag.RUN_METADATA, {"k": "v"})
        w.add_attachment("notes.txt", "text/plain", b"hello", S)
        for i in range(300):
            w.write(CMD, msgs.Twist(linear=msgs.Vector3(x=i)), S + i * S // 10, publisher="mission")
            w.write(ODOM, msgs.Odometry(), S + i * S // 10)
    return path


def _summary(path: Path) -> mcapfile.Layout:
    with open(path, "rb") as f:
        layout = mcapfile.read_summary(f, path.stat().st_size)
    assert layout is not None
    return layout


def test_the_summary_says_what_the_file_holds(log: Path) -> None:
    layout = _summary(log)
    assert layout.has_summary and layout.message_count == 600
    assert len(layout.chunks) > 5 and [c.number for c in layout.chunks][:3] == [1, 2, 3]
    by_topic = {c.topic: c for c in layout.channels.values()}
    assert by_topic[CMD].publisher == "mission" and by_topic[ODOM].publisher == "sim"
    assert by_topic[CMD].msgtype == msgs.Twist.__msgtype__
    assert layout.metadata[bag.RUN_METADATA] == {"k": "v"}
    assert layout.attachments == {"notes.txt": b"hello"}
    assert (layout.start_ns, layout.end_ns) == (S, S + 299 * S // 10)
    with open(log, "rb") as f:
        assert mcapfile.data_crc_matches(f, layout) is True
        assert mcapfile.header_problem(f, log.stat().st_size) == ""


def test_chunk_messages_checks_then_filters_by_topic(log: Path) -> None:
    layout = _summary(log)
    size = log.stat().st_size
    got: list[tuple[str, int]] = []
    with open(log, "rb") as f:
        for ref in layout.chunks:
            got += [
                (info.topic, t)
                for info, t, _ in mcapfile.chunk_messages(f, ref, size, layout, {CMD})
            ]
            assert ref.message_count == mcapfile.indexed_count(f, ref, size)
    assert len(got) == 300 and {topic for topic, _ in got} == {CMD}
    assert [t for _, t in got] == sorted(t for _, t in got)


def test_a_flipped_byte_is_found_by_its_chunk_and_the_data_crc(log: Path, tmp_path: Path) -> None:
    layout = _summary(log)
    ref = layout.chunks[2]
    data = bytearray(log.read_bytes())
    data[ref.offset + ref.length - 20] ^= 0xFF  # inside the chunk's (uncompressed) records
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(bytes(data))
    with open(bad, "rb") as f:
        assert mcapfile.data_crc_matches(f, layout) is False
        with pytest.raises(mcapfile.Broken, match="chunk 3 fails its CRC check") as caught:
            list(mcapfile.chunk_messages(f, ref, len(data), layout))
    assert caught.value.offset == ref.offset


def test_a_cut_file_has_no_summary_and_a_scan_reads_what_is_there(
    log: Path, tmp_path: Path
) -> None:
    data = log.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    size = cut.stat().st_size
    with open(cut, "rb") as f:
        assert mcapfile.read_summary(f, size) is None
        layout = mcapfile.scan(f, size)
    assert not layout.has_summary and layout.stopped_at is not None
    assert 0 < len(layout.chunks) < len(_summary(log).chunks)
    assert all(not c.problem for c in layout.chunks)
    assert layout.start_ns == S and S < layout.end_ns < S + 299 * S // 10
    assert sum(layout.channel_counts.values()) > 0


@pytest.mark.parametrize(
    ("opcode", "why"),
    [(0x02, "wrong record type"), (0x7F, "unknown record type 0x7f at byte 8")],
)
def test_a_damaged_header_stops_the_scan_at_once(
    log: Path, tmp_path: Path, opcode: int, why: str
) -> None:
    data = bytearray(log.read_bytes())
    data[len(mcapfile.MAGIC)] = opcode  # the header record's opcode: a footer's, or none
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(bytes(data))
    with open(bad, "rb") as f:
        problem = mcapfile.header_problem(f, len(data))
        layout = mcapfile.scan(f, len(data))
    assert problem == f"the header record is damaged ({why})"
    assert layout.problems == [problem] and layout.stopped_at == len(mcapfile.MAGIC)
