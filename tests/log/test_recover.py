"""log/recover: the readable messages of a cut log copied into a new, whole log; on a real log
written by usar's writer and cut as a killed recorder leaves it."""

from __future__ import annotations

from pathlib import Path

import pytest

from usar_replay.core import contract, msgs
from usar_replay.core.errors import UsageError
from usar_replay.log import bag
from usar_replay.log.recover import default_output, recover

S = 1_000_000_000


def _log(path: Path, n: int = 400) -> Path:
    with bag.BagWriter(path, chunk_size=2048) as w:
        w.add_metadata(bag.RUN_METADATA, {"mission": "test"})
        w.add_attachment("notes.toml", "application/toml", b"a = 1\n", S)
        for i in range(n):
            w.write(
                contract.ROSOUT, msgs.Log(name="explorer", msg=f"line {i:04d}"), S + i * S // 10
            )
    return path


def _cut(src: Path, dst: Path, fraction: float) -> Path:
    data = src.read_bytes()
    dst.write_bytes(data[: int(len(data) * fraction)])
    return dst


def test_default_output_names() -> None:
    assert default_output(Path("/d/run.mcap")) == Path("/d/run.recovered.mcap")
    assert default_output(Path("/nonexistent/run.mcap.part")) == Path("/nonexistent/run.mcap")
    assert default_output(Path("/d/run")) == Path("/d/run.recovered.mcap")


def test_a_cut_log_is_recovered_up_to_where_it_is_readable(tmp_path: Path) -> None:
    whole = _log(tmp_path / "whole.mcap")
    cut = _cut(whole, tmp_path / "run.mcap.part", 0.6)
    got = recover(cut)
    assert got.output == tmp_path / "run.mcap"
    assert 0 < got.messages < 400
    assert got.describe().startswith(f"recovered {got.messages}")
    assert got.describe().endswith(f"from {cut} into {got.output}, marked interrupted")
    reader = bag.BagReader(got.output, check="full")
    assert reader.damage is None and reader.status == "interrupted"
    texts = [m.msg.msg for m in reader.messages() if isinstance(m.msg, msgs.Log)]
    assert texts == [f"line {i:04d}" for i in range(got.messages)]  # the prefix, in order
    assert reader.end_ns == got.last_time_ns
    assert reader.attachments["notes.toml"] == b"a = 1\n"
    assert reader.metadata[bag.RUN_METADATA] == {"mission": "test"}


def test_a_whole_log_an_empty_cut_and_an_existing_output_are_refused(tmp_path: Path) -> None:
    whole = _log(tmp_path / "whole.mcap", n=5)
    with pytest.raises(UsageError, match="the log is whole; there is nothing to recover"):
        recover(whole)
    cut = _cut(_log(tmp_path / "big.mcap"), tmp_path / "cut.mcap", 0.6)
    taken = tmp_path / "taken.mcap"
    taken.write_bytes(b"mine")
    with pytest.raises(UsageError, match="exists; pass --overwrite"):
        recover(cut, taken)
    assert taken.read_bytes() == b"mine"
    assert recover(cut, taken, overwrite=True).output == taken
    assert bag.BagReader(taken).message_count > 0
    head = _cut(whole, tmp_path / "head.mcap", 0.02)
    with pytest.raises(UsageError):
        recover(head, tmp_path / "none.mcap")
    assert not (tmp_path / "none.mcap").exists()
