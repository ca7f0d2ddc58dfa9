"""Seconds to write a recording's ``.rrd`` with `usar view --save` (printed, not asserted).

    python bench/bench_view.py [LOG.mcap ...]   # default: recordings/course.mcap

Measures :func:`usar_replay.viewer.view.view_run` on an opened run (module imports excluded; the log
is opened for each repeat, as the command does), three times,
and prints the best and the median with camera frames per second. On the course log (477 sim-s,
4776 frames of 640x480 PNG, 71736 messages) the write took about 5 s on a 2-core machine.
The time splits roughly evenly between reading the MCAP, decoding CDR and collecting columns;
rerun itself writes the columns in a fraction of a second (images go in 8 MB chunks).
"""

from __future__ import annotations

import statistics
import sys
import tempfile
import time
from pathlib import Path

from usar_replay.core.contract import IMAGE
from usar_replay.log.run import open_run
from usar_replay.viewer.view import view_run
from usar_replay.viewer.viewer_process import Output

DEFAULT_LOG = Path("recordings/course.mcap")


def bench(log: Path, repeats: int = 3, *, grade: bool = False) -> None:
    """Write ``log``'s view ``repeats`` times into a temporary directory and print the timings."""
    reader = open_run(log).reader
    topic = reader.topics.get(IMAGE)
    frames = topic.count if topic else 0
    sim_s = (reader.end_ns - reader.start_ns) / 1e9
    times: list[float] = []
    size = 0
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "bench.rrd"
        for _ in range(repeats):
            t0 = time.perf_counter()
            view_run(open_run(log), Output(rrd=out), grade=grade, overwrite=True)
            times.append(time.perf_counter() - t0)
            size = out.stat().st_size
    best, median = min(times), statistics.median(times)
    label = " --grade" if grade else ""
    print(
        f"{log.name}{label}: {sim_s:.0f} sim-s, {reader.message_count} messages, {frames} frames "
        f"-> {size / 1e6:.0f} MB .rrd in {best:.2f} s best, {median:.2f} s median "
        f"({frames / best:.0f} frames/s, {sim_s / best:.0f}x real time)"
    )


def main(argv: list[str]) -> None:
    logs = [Path(a) for a in argv] or ([DEFAULT_LOG] if DEFAULT_LOG.exists() else [])
    if not logs:
        print(f"no log given and {DEFAULT_LOG} does not exist; record one with `usar record`")
        return
    for log in logs:
        bench(log)
        bench(log, grade=True)


if __name__ == "__main__":
    main(sys.argv[1:])
