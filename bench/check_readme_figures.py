"""Check the README's figures about a course run against a fresh measurement (within 2x).

    python bench/check_readme_figures.py                  # records the course world (minutes)
    python bench/check_readme_figures.py --log LOG.mcap --record-wall S   # an existing course log

Why: the README's numbers (how long the set-up's recording takes, how big the log is, how big
and how fast its ``.rrd`` is) went stale as the code got faster and the default encoding
changed, and nothing noticed. This script records the built-in course world with ``usar record``
(as the set-up command does), writes its view as ``usar view --save`` does, reads each figure
out of README.md by the sentence it sits in, and prints README against measured. It exits 1
when a figure is more than 2x off either way (wall times depend on the machine: the README's
are for a 2-core machine), 2 when a sentence it looks for is gone from the README.
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
FACTOR = 2.0


@dataclass(frozen=True)
class Measured:
    """One course run's figures."""

    record_wall_s: float
    sim_s: float
    log_mb: float
    frames: int
    rrd_mb: float
    rrd_s: float


def _number(text: str) -> float:
    return float(text.replace(",", ""))


# (figure, regex over the README with one group, measured value from a run, unit)
FIGURES: list[tuple[str, str, Callable[[Measured], float], str]] = [
    ("set-up: sim minutes", r"about (\d+) sim-minutes", lambda m: m.sim_s / 60, "min"),
    (
        "set-up: wall minutes",
        r"about ([\d.]+) minutes of wall time on a quiet 2-core machine, ([\d.]+) on a busy one",
        lambda m: m.record_wall_s / 60,
        "min",
    ),
    (
        "log: MB (JPEG)",
        r"course recording at 640x480@10 Hz is about ([\d.]+) MB",
        lambda m: m.log_mb,
        "MB",
    ),
    ("log: frames", r"the default JPEG \(([\d,]+) frames", lambda m: m.frames, ""),
    (
        "log: MB per sim-minute",
        r"frames, ([\d.]+) MB per sim-minute",
        lambda m: m.log_mb / (m.sim_s / 60),
        "MB",
    ),
    (
        "rrd: frames",
        r"the `\.rrd` of an 8-minute course run \(([\d,]+) frames",
        lambda m: m.frames,
        "",
    ),
    ("rrd: MB", r"course run \([\d,]+ frames, ([\d.]+) MB\)", lambda m: m.rrd_mb, "MB"),
    ("rrd: seconds to write", r"MB\) is written in about ([\d.]+) s", lambda m: m.rrd_s, "s"),
]


def measure(log: Path | None, record_wall_s: float | None, work: Path) -> Measured:
    """Record the course (unless ``log``), then read it and write its view."""
    from usar_replay.core.contract import IMAGE
    from usar_replay.log.run import open_run
    from usar_replay.viewer.view import view_run
    from usar_replay.viewer.viewer_process import Output

    if log is None:
        log = work / "course.mcap"
        began = time.perf_counter()
        subprocess.run(
            [sys.executable, "-m", "usar_replay.cli", "record", "--out", str(log), "--quiet"],
            check=True,
        )
        record_wall_s = time.perf_counter() - began
    run = open_run(log)
    topic = run.reader.topics.get(IMAGE)
    rrd = work / "course.rrd"
    began = time.perf_counter()
    view_run(open_run(log), Output(rrd=rrd))
    rrd_s = time.perf_counter() - began
    return Measured(
        record_wall_s=record_wall_s if record_wall_s is not None else float("nan"),
        sim_s=(run.reader.end_ns - run.reader.start_ns) / 1e9,
        log_mb=log.stat().st_size / 1e6,
        frames=topic.count if topic else 0,
        rrd_mb=rrd.stat().st_size / 1e6,
        rrd_s=rrd_s,
    )


def compare(readme: str, m: Measured) -> tuple[list[str], int]:
    """Lines of README against measured, and the exit code (0, 1 off by more than 2x, 2 gone)."""
    readme = " ".join(readme.split())  # a sentence may be wrapped anywhere
    lines = [f"{'figure':<26} {'README':>10} {'measured':>10} {'ratio':>6}"]
    code = 0
    for name, pattern, get, unit in FIGURES:
        found = re.search(pattern, readme)
        if found is None:
            lines.append(f"{name:<26} the README no longer says this: {pattern!r}")
            code = max(code, 2)
            continue
        # one figure, or a range (quiet machine .. busy machine): within 2x of the range
        lo, hi = _number(found.group(1)), _number(found.group(found.lastindex or 1))
        said = f"{lo:g}" if lo == hi else f"{lo:g}-{hi:g}"
        got = float(get(m))
        if got != got:  # NaN: not measured (a given log without --record-wall)
            lines.append(f"{name:<26} {said:>10} {'-':>10} {'':>6}  not measured")
            continue
        ratio = got / lo if got < lo else got / hi if got > hi else 1.0
        ok = 1 / FACTOR <= ratio <= FACTOR
        code = code if ok else max(code, 1)
        lines.append(
            f"{name:<26} {said:>10} {got:>10.4g} {ratio:>6.2f}  {'ok' if ok else 'OFF'} {unit}"
        )
    return lines, code


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    p.add_argument("--log", type=Path, help="an existing course recording (default: record one)")
    p.add_argument("--record-wall", type=float, help="seconds the given log took to record")
    args = p.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        m = measure(args.log, args.record_wall, Path(tmp))
    lines, code = compare(README.read_text(encoding="utf-8"), m)
    print("\n".join(lines))
    print(f"{'within 2x' if code == 0 else 'NOT within 2x'} ({m})")
    return code


if __name__ == "__main__":
    sys.exit(main())
