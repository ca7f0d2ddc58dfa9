"""Red team (issue #33, points 4 and 9): a log is hostile input.

A crafted log must not exhaust the reader's memory or time (a chunk that expands to gigabytes, a
ROS 1 definition of megabytes), and no string read from it may reach a terminal raw. Each reader
runs as a user runs it, ``usar CMD`` in a subprocess, here under a 1 GiB address-space limit and
a timeout: it must end quickly with exit 3 and one line naming the damage.
"""

from __future__ import annotations

import contextlib
import os
import resource
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from conftest import one_room

from usar_replay.core import msgs, ros1msg
from usar_replay.core.contract import SCENARIO_ATTACHMENT
from usar_replay.log import bag, mcapfile
from usar_replay.world.scenario_toml import to_toml

MEMORY = 1 << 30
"""The readers' address-space limit (RLIMIT_AS): a bomb that is expanded fails under it."""
TIMEOUT_S = 30.0
"""Far above what a capped read takes (about 1 s, most of it Python's start-up)."""


def _limited() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY, MEMORY))


def usar_limited(log: Path, *args: str) -> tuple[subprocess.CompletedProcess[bytes], float]:
    """``usar ARGS`` in ``log``'s folder (names given relative to it keep the one-line note
    whole) under :data:`MEMORY` and :data:`TIMEOUT_S`: the result (bytes: what the terminal
    would receive) and the seconds it took."""
    start = time.monotonic()
    out = subprocess.run(
        [sys.executable, "-m", "usar_replay.cli", *args],
        capture_output=True,
        timeout=TIMEOUT_S,
        preexec_fn=_limited,  # only setrlimit: safe before exec
        check=False,
        env={**os.environ, "COLUMNS": "100"},
        cwd=log.parent,
    )
    return out, time.monotonic() - start


def zstd_bomb(size: int) -> bytes:
    """A zstd frame that expands to ``size`` zero bytes: one 4-byte RLE block per 128 KiB (a
    2 GiB bomb is 64 KiB), built by hand (compressing 2 GiB would take the test's time)."""
    block = 128 * 1024
    full, rest = divmod(size, block)
    sizes = [block] * full + ([rest] if rest else [])
    out = [b"\x28\xb5\x2f\xfd", bytes([0x00, 0x38])]  # magic; no content size; 128 KiB window
    for i, n in enumerate(sizes):
        head = (n << 3) | (1 << 1) | (i == len(sizes) - 1)  # RLE block, last flag
        out.append(head.to_bytes(3, "little") + b"\0")
    return b"".join(out)


def lz4_bomb(size: int) -> bytes:
    """An lz4 frame that expands to ``size`` zero bytes (1 GiB: about 4.2 MiB), streamed."""
    import lz4.frame  # type: ignore[import-untyped]

    comp = lz4.frame.LZ4FrameCompressor()
    zeros = b"\0" * (64 << 20)
    parts = [comp.begin()]
    for _ in range(size // len(zeros)):
        parts.append(comp.compress(zeros))
    parts.append(comp.flush())
    return b"".join(parts)


@contextlib.contextmanager
def crafted_chunk(
    number: int, data: bytes, declared: int, crc: int | None = None
) -> Iterator[None]:
    """While writing a log, make its ``number``-th chunk (1-based) hold ``data`` and declare
    ``declared`` bytes uncompressed (the compression name stays the writer's), and ``crc`` as
    its CRC when given (0: none recorded)."""
    import mcap.writer

    real = mcap.writer.Chunk
    seen = 0

    def chunk(**fields: object) -> object:
        nonlocal seen
        seen += 1
        if seen == number:
            fields = {**fields, "data": data, "uncompressed_size": declared}
            if crc is not None:
                fields["uncompressed_crc"] = crc
        return real(**fields)  # type: ignore[arg-type]

    mcap.writer.Chunk = chunk  # type: ignore[assignment,misc]
    try:
        yield
    finally:
        mcap.writer.Chunk = real  # type: ignore[misc]


def write_log(path: Path, compression: str = "zstd") -> None:
    """A small closed log (the one-room world, 40 ``cmd_vel`` messages) in several chunks."""
    with bag.BagWriter(path, chunk_size=200, compression=compression) as w:
        w.add_attachment(SCENARIO_ATTACHMENT, "application/toml", to_toml(one_room()).encode())
        for i in range(40):
            w.write("/explorer/cmd_vel", msgs.Twist(), (i + 1) * 100_000_000, publisher="mission")


def _words(out: bytes) -> str:
    """What a command printed with its wrapped lines joined."""
    return " ".join(out.decode().split())


def assert_one_damage_line(
    out: subprocess.CompletedProcess[bytes], took: float, *needles: str
) -> None:
    """Exit 3 within seconds, no traceback, ``needles`` in one line: ``usar info`` names the
    damage in its report's ``Damage:`` field, with nothing on stderr; the others say in one
    stderr line that the log is incomplete (shortened to 100 columns: ``usar info`` says the
    rest)."""
    err, shown = out.stderr.decode(), out.stdout.decode()
    assert out.returncode == 3, err
    assert "Traceback" not in err and "MemoryError" not in err, err
    lines = err.strip().splitlines()
    if out.args[3] == "info":
        assert not lines and "Damage:" in shown, err
        text = " ".join(shown.split())  # its fields are wrapped
    else:
        assert len(lines) == 1, err
        text = lines[0]
    for needle in needles:
        assert needle in text, (needle, text)
    assert took < 15, f"took {took:.1f} s"


@pytest.mark.parametrize("command", ["info", "echo", "grade"])
def test_a_chunk_declaring_two_gib_is_damaged_not_allocated(tmp_path: Path, command: str) -> None:
    log = tmp_path / "bomb.mcap"
    with crafted_chunk(2, zstd_bomb(2 << 30), 2 << 30):
        write_log(log)
    args = {"info": [], "echo": ["/explorer/cmd_vel"], "grade": []}[command]
    out, took = usar_limited(log, command, log.name, *args)
    # grade: this log lacks what a grade needs, which it says once the damaged chunk is skipped
    said = {"info": "chunk 2 of", "echo": "the log is incomplete", "grade": "cannot be graded"}
    assert_one_damage_line(out, took, said[command])
    if command == "info":
        assert f"a chunk is at most {mcapfile.MAX_CHUNK_BYTES:,}" in _words(out.stdout)


@pytest.mark.parametrize("compression", ["zstd", "lz4"])
def test_a_chunk_that_expands_past_what_it_declares_stops_there(
    tmp_path: Path, compression: str
) -> None:
    """A small declared size (under the cap), a gigabyte of data: decompression stops at the
    declared size, and the chunk is damaged; the other chunks are still read."""
    log = tmp_path / "bomb.mcap"
    data = zstd_bomb(1 << 30) if compression == "zstd" else lz4_bomb(1 << 30)
    with crafted_chunk(3, data, 1 << 20):
        write_log(log, compression)
    out, took = usar_limited(log, "info", log.name)
    assert_one_damage_line(out, took, "chunk 3 of")
    assert "decompresses to more than the 1,048,576 bytes it declares" in _words(out.stdout)
    echo, took = usar_limited(log, "echo", log.name, "/explorer/cmd_vel")
    assert_one_damage_line(echo, took, "the log is incomplete")
    assert echo.stdout.decode().count("---") > 30  # the intact chunks' messages


def test_a_chunk_of_zeros_is_damaged_at_its_first_record(tmp_path: Path) -> None:
    """64 MiB of zeros that say so (size and CRC 0 as declared) is 7 million empty records of
    type 0: refused at the first, not walked (a chunk holds schemas, channels and messages)."""
    log = tmp_path / "zeros.mcap"
    with crafted_chunk(2, zstd_bomb(mcapfile.MAX_CHUNK_BYTES), mcapfile.MAX_CHUNK_BYTES, crc=0):
        write_log(log)
    reader = bag.BagReader(log)
    start = time.monotonic()
    assert sum(1 for _ in reader.messages()) > 30
    assert time.monotonic() - start < 5
    assert reader.damage is not None
    assert "holds a record that has no place in a chunk" in reader.damage.reason


def test_a_scan_skips_a_chunk_record_too_big_to_read(tmp_path: Path) -> None:
    """Without a summary (a killed recorder's ``.part``) the file is walked: a chunk record of
    more than the cap is damaged and skipped, and the walk goes on past it."""
    whole = tmp_path / "whole.mcap"
    write_log(whole, "none")
    data = bytearray(whole.read_bytes())
    layout = mcapfile.read_summary(open(whole, "rb"), len(data))  # noqa: SIM115 - read once
    assert layout is not None
    second = layout.chunks[1]
    # the second chunk grows to 65 MiB of padding: a record the reader must not load
    pad = 65 << 20
    body_len = int.from_bytes(data[second.offset + 1 : second.offset + 9], "little")
    data[second.offset + 1 : second.offset + 9] = (body_len + pad).to_bytes(8, "little")
    end = second.offset + second.length
    cut = layout.data_end_offset  # no summary: the scan's path
    part = tmp_path / "cut.mcap"
    with open(part, "wb") as f:
        f.write(data[:end])
        f.write(b"\0" * pad)
        f.write(data[end:cut])
    out, took = usar_limited(part, "info", part.name)
    assert_one_damage_line(out, took, "cut.mcap")
    shown = _words(out.stdout)
    assert "chunk 2 is a record of" in shown and "a chunk is at most" in shown
    reader = bag.BagReader(part)
    assert reader.chunk_count == len(layout.chunks)  # the walk went past it
    assert sum(1 for _ in reader.messages()) > 30


def test_an_eight_megabyte_ros1_definition_is_refused_quickly(tmp_path: Path) -> None:
    log = tmp_path / "def.mcap"
    definition = "".join(f"int32 f{i}\n" for i in range(800_000))[:8_000_000]
    with bag.BagWriter(log) as w:
        for i in range(3):
            message = ros1msg.Ros1Message(msgtype="p/Big", definition=definition, data=b"")
            w.write_ros1("/big", message, (i + 1) * 100_000_000, publisher="mission")
    out, took = usar_limited(log, "echo", log.name, "/big")
    err = out.stderr.decode()
    assert out.returncode == 3, err
    assert err.count("\n") == 1 and err.startswith("usar: error: "), err
    assert "definition" in err and "at most" in err, err
    assert took < 15, f"took {took:.1f} s"


# --- point 9: a log's strings never reach a terminal raw -----------------------------------

EVIL = "\x1b]0;pwned\x07\x1b[2J\x9b31m\u202e"
"""A window title (OSC ... BEL), a cleared screen (CSI 2J), C1's one-byte CSI and a
right-to-left override: what a crafted log puts in every string it holds."""
EVIL_TOPIC = f"/evil{EVIL}"


def _raw_controls(data: bytes) -> list[str]:
    """The control characters (C0 but newline and tab, DEL, C1, U+202E) that ``data`` would
    send a terminal."""
    text = data.decode("utf-8", errors="replace")
    return sorted(
        {
            repr(ch)
            for ch in text
            if (ord(ch) < 0x20 and ch not in "\n\t") or 0x7F <= ord(ch) <= 0x9F or ch == "\u202e"
        }
    )


def write_evil_log(path: Path) -> None:
    """A gradable log (the one-room world, its ground truth and ``/tf``) whose every string is
    :data:`EVIL`: topic, type and schema names, metadata, the status reason, ``mission.toml``
    and ``ros1.toml``, a node's name and output, ``/rosout``'s name and text, a frame id."""
    from logtools import Synthetic

    from usar_replay.core import contract
    from usar_replay.log.ros1_run import ParameterRead, Ros1Node, Ros1Run
    from usar_replay.log.run import MissionInfo

    room = one_room()
    s = Synthetic(path, room)
    w = s.w
    w.add_metadata(bag.RUN_METADATA, {f"host{EVIL}": f"value{EVIL}"})
    mission = MissionInfo(f"ros1:evil{EVIL}", f"ros1:evil{EVIL}", EVIL, EVIL).to_toml()
    w.add_attachment(contract.MISSION_ATTACHMENT, "application/toml", mission.encode())
    ros1 = Ros1Run(
        package=f"pkg{EVIL}",
        path=f"/home/{EVIL}",
        launch=f"go{EVIL}.launch",
        nodes=(Ros1Node(f"/node{EVIL}", f"pkg{EVIL}", f"type{EVIL}"),),
        parameters=(ParameterRead(f"/p{EVIL}", f"v{EVIL}", (f"/node{EVIL}",)),),
    )
    w.add_attachment(contract.ROS1_ATTACHMENT, "application/toml", ros1.to_toml().encode())
    w.add_attachment(
        f"{contract.NODE_OUTPUT_ATTACHMENT_PREFIX}node{EVIL}.txt",
        "text/plain",
        f"hello {EVIL}\nbye\r\n".encode(),
    )
    for _ in range(20):
        s.pose("explorer", 0.0, 0.0)
        s.pose("follower", 0.5, 0.0)
        tf = msgs.TFMessage(
            transforms=(
                msgs.TransformStamped(
                    header=msgs.Header(stamp=msgs.Time.from_ns(s.t), frame_id=f"map{EVIL}"),
                    child_frame_id=f"explorer_tf/odom{EVIL}",
                ),
            )
        )
        w.write("/tf", tf, s.t, publisher="sim")
        log = msgs.Log(name=f"/node{EVIL}", msg=f"found {EVIL}", level=msgs.Log.INFO)
        s.write("/rosout", log)
        s.write(EVIL_TOPIC, msgs.Twist())
        message = ros1msg.Ros1Message(msgtype=f"p{EVIL}/T", definition="int32 a\n", data=b"\0" * 4)
        w.write_ros1(f"/ros1{EVIL}", message, s.t, publisher="mission")
        s.advance(0.5)
    w.close(
        "interrupted",
        reason=f"stopped {EVIL}",
        outcome=f"crashed{EVIL}",
        outcome_reason=f"Traceback {EVIL}\nValueError: {EVIL}",
    )


@pytest.fixture(scope="module")
def evil_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("evil") / "evil.mcap"
    write_evil_log(path)
    return path


@pytest.mark.parametrize(
    "args",
    [
        ["info"],
        ["info", "--quick"],
        ["log"],
        ["log", "--output"],
        ["log", "--output", "--node", f"node{EVIL}"],
        ["log", "--output", "--node", "nobody"],  # the error names the nodes there are
        ["echo", "/tf"],
        ["echo", "/rosout"],
        ["echo", EVIL_TOPIC],
        ["echo", f"/ros1{EVIL}"],
        ["echo", "/evil"],  # the error's "did you mean" names the crafted topic
        ["grade"],
        ["grade", "--csv"],
        ["grade", "--junit"],
    ],
    ids=lambda a: " ".join(a).encode("unicode_escape").decode(),
)
def test_no_string_from_a_log_reaches_the_terminal_raw(evil_log: Path, args: list[str]) -> None:
    out, _ = usar_limited(evil_log, args[0], evil_log.name, *args[1:])
    assert "Traceback" not in out.stderr.decode(), out.stderr.decode()
    assert out.stdout or out.stderr  # it printed something
    assert _raw_controls(out.stdout) == [], out.stdout.decode()
    assert _raw_controls(out.stderr) == [], out.stderr.decode()
