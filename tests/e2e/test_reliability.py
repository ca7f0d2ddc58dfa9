"""Reliability as a hostile user tries it: damaged logs, killed recordings, signals, bad options.

The damaged logs are made here from the session's short recording (``room_log``): truncations, bit
flips inside a chunk of camera frames, a corrupt chunk, random bytes over the header, the ``.part``
of a recording killed with SIGKILL. Every command must say exit 3 and one line about it.
"""

from __future__ import annotations

import os
import random
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from clitools import one_error_line, start_usar, usar
from conftest import one_room

from usar_replay.core import msgs
from usar_replay.core.errors import UsageError
from usar_replay.log import bag
from usar_replay.pipeline.record import RecordResult
from usar_replay.world.scenario_toml import save

ROOT = os.geteuid() == 0


def _chunk(path: Path, k: int) -> tuple[int, int]:
    """(offset, length) of chunk ``k`` (0-based) of a log."""
    ref = bag.BagReader(path)._layout.chunks[k]
    return ref.offset, ref.length


def _killed_part(src: Path, part_of: Path) -> Path:
    """A real ``.part``: a writer copying ``src`` is killed with SIGKILL two thirds of the way."""
    code = (
        "import os, signal, sys\n"
        "from usar_replay.log import bag\n"
        "r = bag.BagReader(sys.argv[1]); n = r.message_count * 2 // 3\n"
        "w = bag.BagWriter(sys.argv[2])\n"
        "for a, d in sorted(r.attachments.items()): w.add_attachment(a, 'application/toml', d, 1)\n"
        "for i, m in enumerate(r.messages(decode_messages=False)):\n"
        "    if i == n: os.kill(os.getpid(), signal.SIGKILL)\n"
        "    w.write_raw(m.topic, m.msgtype, m.data, m.log_time_ns)\n"
    )
    proc = subprocess.run([sys.executable, "-c", code, str(src), str(part_of)], check=False)
    assert proc.returncode == -signal.SIGKILL
    part = part_of.with_name(part_of.name + ".part")
    assert part.exists() and not part_of.exists()
    return part


def _bitflip(src: Path, data: bytes, k: int, work: Path) -> bytes:
    """The log with one bit flipped in chunk ``k``, in bytes zstd decompresses without noticing
    (its literals: camera frames), so that only the chunk's CRC can tell. A flip in zstd's own
    sequence data is caught by zstd first, and which byte is which depends on the log's content:
    the first offset from a third of the way in whose flip fails the CRC is taken."""
    off, length = _chunk(src, k)
    probe = work / "bitflip-probe.mcap"
    for pos in range(length // 3, length, 101):
        flipped = bytearray(data)
        flipped[off + pos] ^= 0x04
        probe.write_bytes(bytes(flipped))
        damage = bag.BagReader(probe).damage
        if damage is not None and "CRC" in damage.reason:
            probe.unlink()
            return bytes(flipped)
    raise AssertionError(f"no single bit flip in chunk {k} passes zstd")


@pytest.fixture(scope="session")
def corpus(
    room_log: tuple[Path, RecordResult], tmp_path_factory: pytest.TempPathFactory
) -> dict[str, Path]:
    """Damaged copies of the room recording, by kind of damage."""
    src, _ = room_log
    d = tmp_path_factory.mktemp("damaged")
    data = src.read_bytes()
    out: dict[str, Path] = {}

    def put(name: str, content: bytes) -> None:
        out[name] = d / f"{name}.mcap"
        out[name].write_bytes(content)

    put("truncated-half", data[: len(data) // 2])
    put("truncated-footer", data[:-100])
    put("bitflip-frames", _bitflip(src, data, 2, d))
    off, _ = _chunk(src, 1)
    corrupt = bytearray(data)
    corrupt[off + 200 : off + 500] = bytes(300)
    put("corrupt-chunk", bytes(corrupt))
    rng = random.Random(13)
    header = bytearray(data)
    header[9:29] = bytes(rng.randrange(256) for _ in range(20))
    put("header-bytes", bytes(header))
    out["killed-part"] = _killed_part(src, d / "killed.mcap")
    return out


DAMAGE = [
    "truncated-half",
    "truncated-footer",
    "bitflip-frames",
    "corrupt-chunk",
    "header-bytes",
    "killed-part",
]


def _one_usar_line(out: subprocess.CompletedProcess[str], code: int) -> str:
    assert out.returncode == code, (out.returncode, out.stderr[-2000:])
    assert "Traceback" not in out.stderr
    lines = [x for x in out.stderr.strip().splitlines() if x.strip()]
    assert len(lines) == 1 and lines[0].startswith("usar: "), out.stderr
    return lines[0]


@pytest.mark.parametrize("damage", DAMAGE)
def test_info_detects_the_damage_and_says_what_to_do(corpus: dict[str, Path], damage: str) -> None:
    out = usar("info", str(corpus[damage]))
    assert out.returncode == 3, out.stderr
    assert "Traceback" not in out.stderr
    assert max(len(line) for line in out.stdout.splitlines()) <= 100
    text = " ".join(out.stdout.split())  # lines are wrapped at 100 columns
    assert "Damage: " in text and "messages up to sim time" in text
    assert "usar recover" in text


# replay and view take seconds each: they see one log of each reading path (a scan of a file
# without a summary, a chunk failing its CRC, a damaged header over intact chunks)
SLOW = ["truncated-half", "bitflip-frames", "header-bytes", "killed-part"]


@pytest.mark.parametrize(
    ("command", "damage"),
    [("grade", d) for d in DAMAGE] + [(c, d) for c in ("replay", "view") for d in SLOW],
)
def test_every_command_exits_3_with_one_line(
    corpus: dict[str, Path], damage: str, command: str, tmp_path: Path
) -> None:
    args = [command, str(corpus[damage])]
    if command == "view":
        args += ["--save", str(tmp_path / "v.rrd")]
    line = _one_usar_line(usar(*args), 3)
    assert str(corpus[damage]) in line


def test_damage_says_what_and_how_much(corpus: dict[str, Path]) -> None:
    flip = bag.BagReader(corpus["bitflip-frames"])
    assert flip.damage is not None and "chunk 3 of" in flip.damage.reason
    assert "CRC" in flip.damage.reason
    assert 0 < flip.damage.messages_read < (flip.damage.messages_total or 0)
    head = bag.BagReader(corpus["header-bytes"])
    assert head.damage is not None and "header" in head.damage.reason
    assert head.damage.messages_read == head.damage.messages_total  # the messages are intact
    # what messages() yields matches what the damage says was readable
    assert sum(1 for _ in flip.messages(decode_messages=False)) == flip.damage.messages_read


def test_quick_info_trusts_the_summary(corpus: dict[str, Path]) -> None:
    assert usar("info", "--quick", str(corpus["bitflip-frames"])).returncode == 0
    assert usar("info", str(corpus["bitflip-frames"])).returncode == 3


def test_recover_a_killed_recording(corpus: dict[str, Path], tmp_path: Path) -> None:
    part = tmp_path / "run.mcap.part"
    shutil.copy(corpus["killed-part"], part)
    info = usar("info", str(part))
    # a path longer than a line is broken across lines (cli.textout.wrap): compare without them
    assert info.returncode == 3 and f"usarrecover{part}" in "".join(info.stdout.split())
    out = usar("recover", str(part))
    assert out.returncode == 0, out.stderr
    fixed = tmp_path / "run.mcap"
    assert f"into{fixed}" in "".join(out.stdout.split()) and "marked interrupted" in out.stdout
    r = bag.BagReader(fixed, check="full")
    assert r.has_summary and r.damage is None and r.status == "interrupted"
    assert f"recovered {r.message_count} " in out.stdout and r.message_count > 0
    assert "scenario.toml" in r.attachments
    # the recovered log is an ordinary indexed MCAP for other tools too
    from mcap.reader import make_reader

    with open(fixed, "rb") as f:
        summary = make_reader(f).get_summary()
        assert summary is not None and summary.statistics is not None
        assert summary.statistics.message_count == r.message_count
    # never over an existing file; by default a second recovery takes a free name
    one_error_line(usar("recover", str(part), "-o", str(fixed)), 2, "exists")
    again = usar("recover", str(part))
    assert again.returncode == 0 and "run.recovered.mcap" in "".join(again.stdout.split())


def test_recover_copies_what_survives_a_corrupt_chunk(
    corpus: dict[str, Path], tmp_path: Path
) -> None:
    out = tmp_path / "fixed.mcap"
    res = usar("recover", str(corpus["corrupt-chunk"]), "-o", str(out))
    assert res.returncode == 0, res.stderr
    src = bag.BagReader(corpus["corrupt-chunk"])
    assert src.damage is not None
    assert bag.BagReader(out).message_count == src.damage.messages_read


def test_a_whole_log_has_nothing_to_recover(room_log: tuple[Path, RecordResult]) -> None:
    one_error_line(usar("recover", str(room_log[0])), 2, "nothing to recover")


# --- writing: two recordings, a file that appears, signals ---------------------------------


def test_a_second_writer_to_one_output_is_refused(tmp_path: Path) -> None:
    out = tmp_path / "x.mcap"
    first = bag.BagWriter(out)
    with pytest.raises(UsageError, match="another `usar record` is writing"):
        bag.BagWriter(out)
    first.close()
    assert bag.BagReader(out).complete


def test_a_killed_recordings_part_is_not_overwritten(
    corpus: dict[str, Path], tmp_path: Path
) -> None:
    part = tmp_path / "x.mcap.part"
    shutil.copy(corpus["killed-part"], part)
    before = part.read_bytes()
    with pytest.raises(UsageError, match="usar recover"):
        bag.BagWriter(tmp_path / "x.mcap")
    assert part.read_bytes() == before


def test_a_file_that_appears_while_recording_is_kept(tmp_path: Path) -> None:
    out = tmp_path / "x.mcap"
    w = bag.BagWriter(out)
    w.write("/a", msgs.String(data="x"), 1_000_000_000)
    out.write_text("someone else's file")
    with pytest.raises(UsageError, match=r"x\.2\.mcap"):
        w.close()
    assert out.read_text() == "someone else's file"
    assert bag.BagReader(tmp_path / "x.2.mcap").complete


def _handlers_installed(pid: int) -> bool:
    """Whether the process catches SIGTERM (what `usar` does once it is ready for signals)."""
    with open(f"/proc/{pid}/status") as f:
        caught = next(line for line in f if line.startswith("SigCgt:"))
    return bool(int(caught.split()[1], 16) & (1 << (signal.SIGTERM - 1)))


def _record(tmp_path: Path) -> tuple[subprocess.Popen[str], Path]:
    scenario, out = tmp_path / "room.toml", tmp_path / "cut.mcap"
    save(one_room(), scenario)
    return start_usar("record", "--scenario", str(scenario), "--out", str(out)), out


@pytest.mark.parametrize(("sig", "code"), [(signal.SIGTERM, 143), (signal.SIGHUP, 129)])
def test_sigterm_and_sighup_close_a_recording(tmp_path: Path, sig: int, code: int) -> None:
    proc, out = _record(tmp_path)
    assert proc.stderr is not None
    assert proc.stderr.readline().startswith("sim ")  # the run is under way
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == code, err
    assert "Traceback" not in err and "closed and readable, marked interrupted" in err
    r = bag.BagReader(out)
    assert r.has_summary and r.status == "interrupted" and r.message_count > 0
    assert signal.Signals(sig).name in r.metadata[bag.STATUS_METADATA]["reason"]


def test_early_double_ctrl_c_claims_no_file_and_prints_no_noise(tmp_path: Path) -> None:
    proc, out = _record(tmp_path)
    deadline = time.monotonic() + 60
    while not _handlers_installed(proc.pid):  # a condition, not a duration
        assert time.monotonic() < deadline and proc.poll() is None
    proc.send_signal(signal.SIGINT)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "Traceback" not in err and "Exception ignored" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("usar: interrupted"), err
    assert ("closed and readable" in err) == out.exists(), err


# --- command lines --------------------------------------------------------------------------


@pytest.mark.parametrize("value", ["nan", "0", "-1", "inf", "soon"])
def test_max_sim_time_must_be_positive(value: str, tmp_path: Path) -> None:
    out = tmp_path / "x.mcap"
    res = usar("record", "--max-sim-time", value, "--out", str(out))
    one_error_line(res, 2, "--max-sim-time", "--help")
    assert not out.exists() and not Path(str(out) + ".part").exists()


@pytest.mark.parametrize(
    "argv",
    [["record", "--bogus"], ["grade"], ["nosuch"], ["view"], ["record", "--renderer", "x"]],
)
def test_option_errors_are_one_line(argv: list[str]) -> None:
    one_error_line(usar(*argv), 2, "--help")


def test_missing_log_is_a_usage_error(tmp_path: Path) -> None:
    one_error_line(usar("info", str(tmp_path / "none.mcap")), 2, "no such file")


def test_outputs_into_a_read_only_place_are_one_line(tmp_path: Path) -> None:
    ro = Path("/sys") if ROOT else tmp_path / "ro"
    if not ROOT:
        ro.mkdir()
        ro.chmod(0o555)
    one_error_line(usar("scenario", "--out", str(ro / "x.toml")), 2, "cannot write here")
    assert not (ro / "x.toml").exists()
    res = usar("record", "--out", str(ro / "x.mcap"), "--max-sim-time", "1")
    one_error_line(res, 2, "cannot write here")


@pytest.mark.skipif(ROOT, reason="root reads any file: permission denial cannot happen")
@pytest.mark.parametrize("command", ["info", "replay", "view", "grade"])
def test_unreadable_log_is_one_line(
    room_log: tuple[Path, RecordResult], tmp_path: Path, command: str
) -> None:
    p = tmp_path / "locked.mcap"
    shutil.copy(room_log[0], p)
    p.chmod(0)
    one_error_line(usar(command, str(p)), 2, "permission denied")
