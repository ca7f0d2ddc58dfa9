"""What checking a log costs: opening and reading with every CRC checked (printed, not asserted).

    python bench/bench_read.py [LOG.mcap ...]   # default: recordings/course.mcap

For each log, the best of three runs of:

* opening it at each check level of :class:`usar_replay.log.bag.BagReader` (``summary``: trust the
  summary, ``usar info --quick``; ``data``: the data CRC over the whole file, header and
  attachments, what grade/replay/view do; ``full``: every chunk decompressed and CRC-checked,
  what ``usar info`` does);
* reading every message (raw bytes, no CDR decoding) with :meth:`BagReader.messages`, which
  checks each chunk's CRC, against the ``mcap`` library's own reader with CRC checks off, the
  way usar read before.

Each is printed in seconds and as a fraction of the log's sim duration (``0.01x`` = reading one
sim-second takes 10 ms). Module imports are excluded.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from pathlib import Path

from mcap.reader import make_reader

from usar_replay.log.bag import BagReader

DEFAULT_LOG = Path("recordings/course.mcap")


def _best(fn: Callable[[], object], repeats: int = 3) -> float:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def _read_all_checked(log: Path) -> int:
    return sum(1 for _ in BagReader(log, check="summary").messages(decode_messages=False))


def _read_all_unchecked(log: Path) -> int:
    with open(log, "rb") as f:
        return sum(1 for _ in make_reader(f).iter_messages(log_time_order=False))


def bench(log: Path) -> None:
    reader = BagReader(log, check="summary")
    sim_s = max(reader.end_ns - reader.start_ns, 1) / 1e9
    mb = reader.size_bytes / 1e6
    print(
        f"{log}: {mb:.1f} MB, {reader.message_count} messages, {reader.chunk_count} chunks, "
        f"{sim_s:.1f} sim-s, data CRC {'recorded' if reader.data_crc_recorded else 'absent'}"
    )
    rows = [
        (f"open, check={level}", _best(lambda lv=level: BagReader(log, check=lv)))
        for level in ("summary", "data", "full")
    ]
    rows.append(("read all, chunk CRCs checked", _best(lambda: _read_all_checked(log))))
    rows.append(("read all, mcap reader, no CRC", _best(lambda: _read_all_unchecked(log))))
    for name, seconds in rows:
        print(
            f"  {name:<32} {seconds:7.3f} s  {seconds / sim_s:8.4f}x sim time  "
            f"{mb / seconds:7.0f} MB/s"
        )
    checked, unchecked = rows[3][1], rows[4][1]
    print(f"  checked read / unchecked read: {checked / unchecked:.2f}")


def main(argv: list[str]) -> None:
    logs = [Path(a) for a in argv] or [DEFAULT_LOG]
    for log in logs:
        if not log.exists():
            print(f"{log}: no such file; record one with `usar record` or pass a path")
            continue
        bench(log)


if __name__ == "__main__":
    main(sys.argv[1:])
