"""Grading with camera frames in chunks of their own, against the interleaved layout (printed).

    python bench/bench_chunks.py LOG [--repeat 3]

Copies LOG twice, message for message (the same CDR bytes, metadata and attachments): once in
the default layout and once with ``BagWriter(image_chunks=True)``. For each copy it prints the
file size, how many chunks and compressed bytes a reader of the grader's topics has to open,
and the CPU time of grading it (best of ``--repeat``), and the grade's points (equal, or the
layout changed a result).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from mcap.reader import SeekingReader

from usar_replay import bag
from usar_replay.grade import GRADE_TOPICS, grade_file


def copy(src: Path, dst: Path, *, image_chunks: bool) -> None:
    reader = bag.BagReader(src)
    with bag.BagWriter(dst, image_chunks=image_chunks) as w:
        for name, data in sorted(reader.attachments.items()):
            w.add_attachment(name, "application/octet-stream", data, reader.start_ns)
        for name, md in sorted(reader.metadata.items()):
            if name != bag.STATUS_METADATA:
                w.add_metadata(name, md)
        for m in reader.messages(decode_messages=False):
            w.write_raw(m.topic, m.msgtype, m.data, m.log_time_ns)


def chunks_opened(path: Path) -> tuple[int, int, int]:
    """(chunks a grade-topic read opens, all chunks, compressed bytes it opens)."""
    with open(path, "rb") as f:
        summary = SeekingReader(f).get_summary()
    assert summary is not None
    wanted = {cid for cid, ch in summary.channels.items() if ch.topic in GRADE_TOPICS}
    opened = [ci for ci in summary.chunk_indexes if set(ci.message_index_offsets) & wanted]
    return len(opened), len(summary.chunk_indexes), sum(ci.compressed_size for ci in opened)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("log", type=Path)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="usar-chunks-") as tmp:
        print("layout          MB   chunks opened / all   MB opened   grade CPU s  points")
        for label, paired in (("interleaved", False), ("image chunks", True)):
            out = Path(tmp) / f"{label.replace(' ', '-')}.mcap"
            copy(args.log, out, image_chunks=paired)
            n_open, n_all, opened = chunks_opened(out)
            best = float("inf")
            points = 0.0
            for _ in range(args.repeat):
                t0 = time.process_time()
                report = grade_file(out)
                best = min(best, time.process_time() - t0)
                points = report.points
            print(
                f"{label:<13} {out.stat().st_size / 1e6:6.2f}   {n_open:6d} / {n_all:<6d}"
                f"   {opened / 1e6:9.2f}   {best:11.3f}  {points:g}"
            )


if __name__ == "__main__":
    main()
