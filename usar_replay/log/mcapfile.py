"""The MCAP file's structure, checked: records at offsets, CRCs, chunks. Used by :mod:`bag` only.

Why not ``mcap.reader.SeekingReader``: it reads with CRC checks off by default, stops at the first
bad chunk with an exception that cannot be resumed, and trusts the summary without looking at the
data. A damaged log must instead say *what* is damaged (the header, chunk 12 of 80, an attachment,
the summary) and *how much* is still readable, and go on past a bad chunk. So this module walks
the records itself, bounding every length by the file's size before reading it (a flipped length
byte must not make us allocate terabytes), and checks every CRC the format has:

* the **data CRC** (``DataEnd.data_section_crc``: every byte from the magic to the data end; 0 in
  logs written before usar enabled it), which also covers the header and the compressed chunks;
* the **chunk CRC** (``Chunk.uncompressed_crc``) of every chunk that is decompressed;
* the **summary CRC** (``Footer.summary_crc``) and each **attachment's CRC**.

Everything streams: at most one chunk (about 1 MiB; never more than :data:`MAX_CHUNK_BYTES`) is
held in memory at a time.
"""

from __future__ import annotations

import io
import struct
import zlib
from collections.abc import Callable, Container, Iterator
from dataclasses import dataclass, field
from typing import IO

import zstandard
from mcap.data_stream import ReadDataStream
from mcap.opcode import Opcode
from mcap.records import (
    Attachment,
    AttachmentIndex,
    Channel,
    Chunk,
    ChunkIndex,
    Footer,
    Header,
    MessageIndex,
    Metadata,
    MetadataIndex,
    Schema,
    Statistics,
)

__all__ = [
    "Broken",
    "ChannelInfo",
    "ChunkRef",
    "Layout",
    "MAGIC",
    "MAX_CHUNK_BYTES",
    "chunk_messages",
    "data_crc_matches",
    "header_problem",
    "indexed_count",
    "read_summary",
    "scan",
]

MAGIC = b"\x89MCAP0\r\n"
_OPCODES = frozenset(int(o) for o in Opcode)
_BLOCK = 1 << 20
MAX_CHUNK_BYTES = 64 * 1024 * 1024
"""The most bytes one chunk may hold once decompressed (64 MiB). usar's writer closes a chunk
past 1 MiB, so its largest is 1 MiB plus one message (at most 8 MiB: the boundary's cap). A
chunk that declares more, or whose data decompresses to more than it declares, is damaged: it
is refused before anything is allocated, and decompression stops at the declared size (a 64 KiB
zstd chunk can expand to gigabytes)."""
_MAX_CHUNK_RECORD = MAX_CHUNK_BYTES + (1 << 20)
"""The longest chunk record read: its data at most :data:`MAX_CHUNK_BYTES` (stored), plus its
fields and what compression may add to incompressible data."""
_FOOTER_LEN = 1 + 8 + 20  # opcode, length, summary_start, summary_offset_start, summary_crc
_DATA_END_LEN = 1 + 8 + 4
_MESSAGE_HEAD = struct.Struct("<HIQQ")  # channel_id, sequence, log_time, publish_time
_RECORD_HEAD = struct.Struct("<BQ")  # opcode, length
_MESSAGE_RECORD_HEAD = struct.Struct("<BQHIQ")  # opcode, length, channel_id, sequence, log_time
_MESSAGE = int(Opcode.MESSAGE)
_MESSAGE_DATA = 9 + _MESSAGE_HEAD.size  # where a message record's data starts


class Broken(Exception):
    """The file's structure is damaged at ``offset``: ``str(err)`` says how, for a person."""

    def __init__(self, offset: int, what: str) -> None:
        super().__init__(what)
        self.offset = offset


PUBLISHER_KEY = "usar.publisher"
"""Channel metadata key: who published the channel's messages (sim, mission, recorder)."""


@dataclass(frozen=True, slots=True)
class ChannelInfo:
    id: int
    topic: str
    msgtype: str
    publisher: str = ""


@dataclass(slots=True)
class ChunkRef:
    """Where one chunk is, what it holds, and (once read) whether it is intact."""

    number: int
    """1-based position among the file's chunks (what a person is told)."""
    offset: int
    length: int
    """The whole record's length in bytes (opcode and length field included)."""
    start_ns: int
    end_ns: int
    channel_ids: frozenset[int] | None = None
    """Channels with messages in the chunk (from the summary); None when unknown."""
    index_offset: int = 0
    index_length: int = 0
    message_count: int | None = None
    problem: str = ""


@dataclass(slots=True)
class Layout:
    """What the file holds, from its summary or from a scan."""

    has_summary: bool = False
    data_end_offset: int = 0
    data_crc: int = 0
    chunks: list[ChunkRef] = field(default_factory=list)
    channels: dict[int, ChannelInfo] = field(default_factory=dict)
    schemas: dict[int, str] = field(default_factory=dict)
    ros1_definitions: dict[str, str] = field(default_factory=dict)
    """``pkg/Type`` -> full definition, for the ``ros1msg`` schemas (a ROS 1 package's own
    types, kept in their own encoding)."""
    channel_counts: dict[int, int] = field(default_factory=dict)
    message_count: int | None = None
    start_ns: int = 0
    end_ns: int = 0
    metadata: dict[str, dict[str, str]] = field(default_factory=dict)
    attachments: dict[str, bytes] = field(default_factory=dict)
    problems: list[str] = field(default_factory=list)
    """Damage found outside the chunks, one phrase each (``the header record is damaged``)."""
    stopped_at: int | None = None
    """A scan's end: the offset where the readable part stops (None: it reached the footer)."""


# --- records --------------------------------------------------------------------------------


def _read_exact(f: IO[bytes], offset: int, n: int, size: int, what: str) -> bytes:
    if n < 0 or offset < 0 or offset + n > size:
        raise Broken(offset, f"{what} runs past the end of the file")
    f.seek(offset)
    data = f.read(n)
    if len(data) != n:
        raise Broken(offset, f"{what} runs past the end of the file")
    return data


def _head_at(f: IO[bytes], offset: int, size: int) -> tuple[int, int]:
    """(opcode, body length) of the record at ``offset``; its length is checked against the
    file."""
    head = _read_exact(f, offset, 9, size, "a record")
    opcode, length = head[0], int.from_bytes(head[1:9], "little")
    if opcode not in _OPCODES:
        raise Broken(offset, f"unknown record type 0x{opcode:02x} at byte {offset}")
    if offset + 9 + length > size:
        raise Broken(offset, f"the record at byte {offset} claims {length} bytes, past the end")
    return opcode, length


def _record_at(f: IO[bytes], offset: int, size: int) -> tuple[int, bytes]:
    """(opcode, body) of the record at ``offset``; its length is checked against the file."""
    opcode, length = _head_at(f, offset, size)
    return opcode, _read_exact(f, offset + 9, length, size, "a record")


def _too_big(length: int, where: str, offset: int) -> Broken:
    return Broken(
        offset,
        f"{where} is a record of {length:,} bytes; a chunk is at most {MAX_CHUNK_BYTES:,} (64 MiB)",
    )


_READERS = {
    Opcode.HEADER: Header.read,
    Opcode.CHANNEL: Channel.read,
    Opcode.SCHEMA: Schema.read,
    Opcode.CHUNK: Chunk.read,
    Opcode.METADATA: Metadata.read,
    Opcode.ATTACHMENT: Attachment.read,
    Opcode.CHUNK_INDEX: ChunkIndex.read,
    Opcode.STATISTICS: Statistics.read,
    Opcode.MESSAGE_INDEX: MessageIndex.read,
    Opcode.METADATA_INDEX: MetadataIndex.read,
    Opcode.ATTACHMENT_INDEX: AttachmentIndex.read,
    Opcode.FOOTER: Footer.read,
}


def _parse(opcode: int, body: bytes, offset: int) -> object:
    """The record of ``body``; a body that does not parse exactly is :class:`Broken`."""
    reader = _READERS.get(Opcode(opcode))
    if reader is None:
        return None
    stream = ReadDataStream(io.BytesIO(body))
    try:
        rec = reader(stream)
    except Exception as err:
        raise Broken(
            offset,
            f"the {Opcode(opcode).name.lower()} record at byte {offset} is "
            f"damaged ({type(err).__name__})",
        ) from err
    if stream.count > len(body):
        raise Broken(
            offset,
            f"the {Opcode(opcode).name.lower()} record at byte {offset} is "
            "damaged (its fields run past its length)",
        )
    return rec


def _attachment_crc_ok(body: bytes) -> bool:
    stored = int.from_bytes(body[-4:], "little")
    return stored == 0 or zlib.crc32(body[:-4]) == stored


# --- summary --------------------------------------------------------------------------------


def read_summary(f: IO[bytes], size: int) -> Layout | None:
    """The layout from the summary, or None when there is none (a file that was not closed) or
    it is damaged (its CRC fails or it does not parse: the caller scans the file instead)."""
    if size < len(MAGIC) * 2 + _FOOTER_LEN:
        return None
    f.seek(size - len(MAGIC))
    if f.read(len(MAGIC)) != MAGIC:
        return None
    footer_at = size - len(MAGIC) - _FOOTER_LEN
    head = _read_exact(f, footer_at, 9, size, "the footer")
    if head[0] != Opcode.FOOTER or int.from_bytes(head[1:9], "little") != 20:
        return None
    summary_start, _, summary_crc = struct.unpack("<QQI", f.read(20))
    if summary_start < len(MAGIC) + _DATA_END_LEN or summary_start > footer_at:
        return None
    section = _read_exact(f, summary_start, footer_at + 9 + 16 - summary_start, size, "summary")
    if summary_crc != 0 and zlib.crc32(section) != summary_crc:
        return None
    layout = Layout(has_summary=True)
    try:
        _fill_from_summary(f, size, section[: footer_at - summary_start], summary_start, layout)
    except Broken:
        return None
    de_at = summary_start - _DATA_END_LEN
    opcode, body = _record_at(f, de_at, size)
    if opcode != Opcode.DATA_END or len(body) != 4:
        return None
    layout.data_end_offset = de_at
    layout.data_crc = int.from_bytes(body, "little")
    return layout


def _note_schema(layout: Layout, rec: Schema) -> None:
    """A schema record: its name, and a ``ros1msg`` schema's definition."""
    layout.schemas[rec.id] = rec.name
    if rec.encoding == "ros1msg":
        layout.ros1_definitions[rec.name] = bytes(rec.data).decode("utf-8", errors="replace")


def _fill_from_summary(f: IO[bytes], size: int, section: bytes, base: int, layout: Layout) -> None:
    channels: list[Channel] = []
    pos = 0
    while pos < len(section):
        if pos + 9 > len(section):
            raise Broken(base + pos, "the summary is damaged")
        opcode, length = section[pos], int.from_bytes(section[pos + 1 : pos + 9], "little")
        body = section[pos + 9 : pos + 9 + length]
        if opcode not in _OPCODES or len(body) != length:
            raise Broken(base + pos, "the summary is damaged")
        rec = _parse(opcode, body, base + pos)
        if isinstance(rec, Schema):
            _note_schema(layout, rec)
        elif isinstance(rec, Channel):
            channels.append(rec)
        elif isinstance(rec, Statistics):
            layout.message_count = rec.message_count
            layout.start_ns, layout.end_ns = rec.message_start_time, rec.message_end_time
            layout.channel_counts = dict(rec.channel_message_counts)
        elif isinstance(rec, ChunkIndex):
            layout.chunks.append(
                ChunkRef(
                    number=0,
                    offset=rec.chunk_start_offset,
                    length=rec.chunk_length,
                    start_ns=rec.message_start_time,
                    end_ns=rec.message_end_time,
                    channel_ids=frozenset(rec.message_index_offsets),
                    index_offset=rec.chunk_start_offset + rec.chunk_length,
                    index_length=rec.message_index_length,
                )
            )
        elif isinstance(rec, MetadataIndex):
            _, mbody = _record_at(f, rec.offset, size)
            md = _parse(Opcode.METADATA, mbody, rec.offset)
            assert isinstance(md, Metadata)
            layout.metadata[md.name] = dict(md.metadata)
        elif isinstance(rec, AttachmentIndex):
            _, abody = _record_at(f, rec.offset, size)
            att = _parse(Opcode.ATTACHMENT, abody, rec.offset)
            assert isinstance(att, Attachment)
            if _attachment_crc_ok(abody):
                layout.attachments[att.name] = bytes(att.data)
            else:
                layout.problems.append(f"the attachment {att.name} fails its CRC check")
        pos += 9 + length
    for ch in channels:
        name = layout.schemas.get(ch.schema_id, "")
        layout.channels[ch.id] = ChannelInfo(
            ch.id, ch.topic, name, ch.metadata.get(PUBLISHER_KEY, "")
        )
    layout.chunks.sort(key=lambda c: c.offset)
    for i, c in enumerate(layout.chunks):
        c.number = i + 1
        if c.offset < len(MAGIC) or c.offset + c.length > size:
            raise Broken(c.offset, "a chunk index points outside the file")


def data_crc_matches(f: IO[bytes], layout: Layout) -> bool | None:
    """Whether the data section's CRC matches (None: the writer recorded none). Streams."""
    if layout.data_crc == 0 or not layout.data_end_offset:
        return None
    f.seek(0)
    crc, left = 0, layout.data_end_offset
    while left > 0:
        block = f.read(min(_BLOCK, left))
        if not block:
            return False
        crc = zlib.crc32(block, crc)
        left -= len(block)
    return crc == layout.data_crc


def header_problem(f: IO[bytes], size: int) -> str:
    """What is wrong with the header record after the magic ('' when it is whole)."""
    try:
        opcode, body = _record_at(f, len(MAGIC), size)
        if opcode != Opcode.HEADER:
            return "the header record is damaged (wrong record type)"
        rec = _parse(opcode, body, len(MAGIC))
        assert isinstance(rec, Header)
        if 8 + len(rec.profile.encode()) + len(rec.library.encode()) != len(body):
            return "the header record is damaged (its length does not match its fields)"
    except Broken as err:
        return f"the header record is damaged ({err})"
    return ""


# --- chunks ---------------------------------------------------------------------------------


def _decompress(chunk: Chunk, where: str, offset: int) -> bytes:
    """The chunk's bytes, never more than it declares nor than :data:`MAX_CHUNK_BYTES`;
    :class:`Broken` (saying which) otherwise."""
    declared = chunk.uncompressed_size
    if declared > MAX_CHUNK_BYTES:
        raise Broken(
            offset,
            f"{where} declares {declared:,} bytes uncompressed; a chunk is at most "
            f"{MAX_CHUNK_BYTES:,} (64 MiB)",
        )
    if chunk.compression == "zstd":
        reader = zstandard.ZstdDecompressor().stream_reader(
            bytes(chunk.data), read_across_frames=True
        )
        data = _read_upto(reader.read, declared + 1)
    elif chunk.compression == "lz4":
        import lz4.frame  # type: ignore[import-untyped]  # optional, as in mcap itself

        lz = lz4.frame.LZ4FrameDecompressor()
        data = bytes(lz.decompress(bytes(chunk.data), max_length=declared + 1))
        if len(data) <= declared and not lz.eof:
            raise Broken(offset, f"{where} cannot be decompressed (its lz4 frame is cut short)")
    elif chunk.compression == "":
        data = bytes(chunk.data)
    else:
        raise Broken(offset, f"{where} cannot be decompressed (unknown compression)")
    if len(data) > declared:
        raise Broken(
            offset, f"{where} decompresses to more than the {declared:,} bytes it declares"
        )
    return data


def _read_upto(read: Callable[[int], bytes], limit: int) -> bytes:
    """At most ``limit`` bytes from a stream (its ``read``), in blocks: the limit is what is
    ever allocated, whatever the compressed data expands to."""
    parts: list[bytes] = []
    got = 0
    while got < limit:
        block = read(min(_BLOCK * 4, limit - got))
        if not block:
            break
        parts.append(block)
        got += len(block)
    return b"".join(parts)


def chunk_messages(
    f: IO[bytes],
    ref: ChunkRef,
    size: int,
    layout: Layout,
    topics: Container[str] | None = None,
) -> Iterator[tuple[ChannelInfo, int, bytes]]:
    """(channel, log time, data) of every message in the chunk, after checking its CRC; only
    those on ``topics`` when given (the others are checked and counted, never copied: most of a
    usar chunk is camera frames that ``usar grade`` skips).

    Channel and schema records found inside the chunk are added to ``layout``. Raises
    :class:`Broken` (saying how) before yielding anything when the chunk is damaged.
    """
    where = f"chunk {ref.number}" if ref.number else f"the chunk at byte {ref.offset}"
    if ref.length > _MAX_CHUNK_RECORD:
        raise _too_big(ref.length, where, ref.offset)
    opcode, body = _record_at(f, ref.offset, size)
    if opcode != Opcode.CHUNK or 9 + len(body) != ref.length:
        raise Broken(ref.offset, f"{where} is not where the index says")
    chunk = _parse(opcode, body, ref.offset)
    assert isinstance(chunk, Chunk)
    try:
        data = _decompress(chunk, where, ref.offset)
    except Broken:
        raise
    except Exception as err:
        raise Broken(ref.offset, f"{where} cannot be decompressed ({_short(err)})") from err
    if len(data) != chunk.uncompressed_size:
        raise Broken(ref.offset, f"{where} has the wrong size after decompression")
    if chunk.uncompressed_crc != 0 and zlib.crc32(data) != chunk.uncompressed_crc:
        raise Broken(ref.offset, f"{where} fails its CRC check (its bytes were changed)")
    found: list[tuple[ChannelInfo, int, bytes]] = []
    channels, schemas = layout.channels, layout.schemas
    record_head, message_head = _RECORD_HEAD.unpack_from, _MESSAGE_RECORD_HEAD.unpack_from
    total = len(data)
    count = 0
    pos = 0
    while pos < total:
        # most records are messages: their head and the record's are read by one unpack (what
        # it reads past a shorter record is never used: that record is not a message or is
        # damaged, and the checks below say so in the same order as for any record)
        if pos + _MESSAGE_RECORD_HEAD.size <= total:
            opcode, length, cid, _, log_time = message_head(data, pos)
        elif pos + 9 > total:
            raise Broken(ref.offset, f"{where} holds a damaged record")
        else:
            opcode, length = record_head(data, pos)
        end = pos + 9 + length
        if end > total:
            raise Broken(ref.offset, f"{where} holds a damaged record")
        if opcode == _MESSAGE:
            if length < _MESSAGE_HEAD.size:
                raise Broken(ref.offset, f"{where} holds a damaged message")
            # here end <= total and length >= 22, so the combined unpack above was taken
            info = channels.get(cid)
            if info is None:
                raise Broken(ref.offset, f"{where} holds a message on an unknown channel {cid}")
            count += 1
            if topics is None or info.topic in topics:
                found.append((info, log_time, data[pos + _MESSAGE_DATA : end]))
        elif opcode == Opcode.SCHEMA:
            rec = _parse(opcode, data[pos + 9 : end], ref.offset)
            assert isinstance(rec, Schema)
            _note_schema(layout, rec)
        elif opcode == Opcode.CHANNEL:
            rec = _parse(opcode, data[pos + 9 : end], ref.offset)
            assert isinstance(rec, Channel)
            info = ChannelInfo(
                rec.id,
                rec.topic,
                schemas.get(rec.schema_id, ""),
                rec.metadata.get(PUBLISHER_KEY, ""),
            )
            channels.setdefault(rec.id, info)
        else:
            # a chunk holds schemas, channels and messages only (MCAP's spec): anything else
            # is damage, and a run of empty records (a chunk of zeros) must not be walked
            raise Broken(ref.offset, f"{where} holds a record that has no place in a chunk")
        pos = end
    ref.message_count = count
    yield from found


def indexed_count(f: IO[bytes], ref: ChunkRef, size: int) -> int | None:
    """How many messages the chunk's message indexes list (None when they cannot be read)."""
    if not ref.index_length:
        return None
    try:
        pos, end, n = ref.index_offset, ref.index_offset + ref.index_length, 0
        while pos < end:
            opcode, body = _record_at(f, pos, size)
            if opcode == Opcode.MESSAGE_INDEX:
                n += max(len(body) - 2 - 4, 0) // 16
            pos += 9 + len(body)
        return n
    except Broken:
        return None


# --- scanning a file without a (good) summary -----------------------------------------------


def scan(f: IO[bytes], size: int) -> Layout:
    """Walk the file record by record from the header: every chunk is decompressed and checked.

    A chunk that fails its checks but whose record is intact is noted and skipped; the walk stops
    at the first record whose structure is broken (nothing after it can be found without an
    index), and :attr:`Layout.stopped_at` says where.
    """
    layout = Layout()
    problem = header_problem(f, size)
    if problem:
        layout.problems.append(problem)
        layout.stopped_at = len(MAGIC)
        return layout
    schemas = layout.schemas
    first = True
    pos, number = len(MAGIC), 0
    while True:
        if pos == size:
            layout.stopped_at = pos
            break
        try:
            opcode, body_length = _head_at(f, pos, size)
            if opcode == Opcode.CHUNK and 9 + body_length > _MAX_CHUNK_RECORD:
                # intact as a record, too big to read: damaged, skipped, and the walk goes on
                number += 1
                ref = ChunkRef(number, pos, 9 + body_length, 0, 0, message_count=0)
                ref.problem = str(_too_big(9 + body_length, f"chunk {number}", pos))
                layout.chunks.append(ref)
                pos += 9 + body_length
                continue
            opcode, body = _record_at(f, pos, size)
        except Broken:
            layout.stopped_at = pos
            break
        length = 9 + len(body)
        if opcode == Opcode.CHUNK:
            number += 1
            try:
                chunk = _parse(opcode, body, pos)
            except Broken:
                layout.stopped_at = pos
                break
            assert isinstance(chunk, Chunk)
            ref = ChunkRef(number, pos, length, chunk.message_start_time, chunk.message_end_time)
            del chunk, body
            try:
                for info, t, _ in chunk_messages(f, ref, size, layout):
                    layout.channel_counts[info.id] = layout.channel_counts.get(info.id, 0) + 1
                    if first:
                        layout.start_ns, first = t, False
                    layout.end_ns = t
            except Broken as err:
                ref.problem = str(err)
            layout.chunks.append(ref)
        elif opcode in (Opcode.SCHEMA, Opcode.CHANNEL, Opcode.METADATA, Opcode.ATTACHMENT):
            try:
                rec = _parse(opcode, body, pos)
            except Broken:
                layout.stopped_at = pos
                break
            if isinstance(rec, Schema):
                _note_schema(layout, rec)
            elif isinstance(rec, Channel):
                layout.channels.setdefault(
                    rec.id,
                    ChannelInfo(
                        rec.id,
                        rec.topic,
                        schemas.get(rec.schema_id, ""),
                        rec.metadata.get(PUBLISHER_KEY, ""),
                    ),
                )
            elif isinstance(rec, Metadata):
                layout.metadata[rec.name] = dict(rec.metadata)
            elif isinstance(rec, Attachment):
                if _attachment_crc_ok(body):
                    layout.attachments[rec.name] = bytes(rec.data)
                else:
                    layout.problems.append(f"the attachment {rec.name} fails its CRC check")
        elif opcode == Opcode.DATA_END:
            layout.data_end_offset = pos
            layout.stopped_at = None
            break
        pos += length
    layout.message_count = None
    return layout


def _short(err: BaseException) -> str:
    text = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
    return text[:100]
