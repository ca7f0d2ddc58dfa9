"""`usar record`'s speed and size, with where the time goes (printed, never asserted).

    python bench/bench_record.py [--course-seconds 120] [--only room|course] [--encoding E]
                                 [--keep DIR] [--latency 0|1] [--camera WxH@HZ]
                                 [--course-detection on|off]

Records the one-room world of the tests (the whole mission: explorer, then follower) and the
first ``--course-seconds`` of sim time of the course world, into a temporary directory, and
prints per world: the real-time factor (sim time / wall time, and sim time / CPU time of both
processes, usar's and the mission's: the second is the fairer figure on a shared machine), MB
per sim-minute, frames rendered against frames recorded, and usar's CPU split by stage:

* ``render``: pybullet renders (frames reused because nothing moved cost nothing here);
* ``encode``: compressing frames (a frame equal to the previous one costs one comparison);
* ``log``: serialising and writing messages; ``physics``: the sim's steps;
* ``detect``: the course's ArUco detector (trusted, on usar's side: issue #21; before it, the
  mission process ran it);
* ``region``: the course camera's region around the markers that can be in view (issue 43:
  finding it, rendering it at 1920x1080's pixel density, PNG), with ``record.course_detection``;
* ``rest``: tf, odometry, the process boundary and the loop itself.

``--course-detection off`` records as before issue 43 (the detector on the 640x480 frames).

``--camera 1920x1080@30`` records with another camera (size and rate; the field of view stays
the scenario's): what the course's own camera (the TurtleBot3 waffle's in Gazebo) would cost
against usar's default (issue #32; the figures are in docs/ros1.md, "The course's camera").

The mission process (image decoding, ArUco detection, planning) is reported as one figure. The
split is measured by wrapping those functions with CPU-time counters; the wrappers cost
microseconds per call. Ratios are to sim time, as the issue asks; nothing here is asserted.
"""

from __future__ import annotations

import argparse
import dataclasses
import resource
import sys
import tempfile
import time
from collections import defaultdict
from collections.abc import Callable
from pathlib import Path
from typing import Any

from usar_replay.core.settings import RecordSettings, RunSettings
from usar_replay.log import bag
from usar_replay.pipeline import record
from usar_replay.sim import simulator as sim
from usar_replay.world.scenario import Scenario, course_world

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from conftest import one_room

STAGES = ("render", "encode", "log", "physics", "detect", "region")
_spent: defaultdict[str, float] = defaultdict(float)
_calls: defaultdict[str, int] = defaultdict(int)


def _timed(stage: str, fn: Callable[..., Any]) -> Callable[..., Any]:
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        t0 = time.process_time()
        _calls[stage] += 1
        try:
            return fn(*args, **kwargs)
        finally:
            _spent[stage] += time.process_time() - t0

    return wrapper


def _instrument() -> None:
    """Wrap each stage's function where the current code has it (names may move; skip if so)."""
    points: list[tuple[Any, str, str]] = [
        (sim.Simulator, "_render", "render"),
        (record, "encode_image", "encode"),
        (bag.BagWriter, "write", "log"),
        (bag.BagWriter, "write_raw", "log"),
        (sim.Simulator, "step", "physics"),
    ]
    try:  # the course's detector, on usar's side since issue #21 (before: in the mission)
        from usar_replay.pipeline import course_detector

        points.append((course_detector, "detect", "detect"))
        points.append((record, "course_view", "region"))
        points.append((sim.Simulator, "render_region", "regions"))  # counted, inside region
    except ImportError:
        pass
    if not hasattr(sim.Simulator, "_render"):  # before frames were reused
        points[0] = (sim.Simulator, "render_camera", "render")
    for owner, name, stage in points:
        if hasattr(owner, name):
            setattr(owner, name, _timed(stage, getattr(owner, name)))


def _children_cpu() -> float:
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


def bench(
    label: str,
    scenario: Scenario,
    max_sim_time: float | None,
    out: Path,
    latency: int,
    course: bool | None = None,
) -> None:
    _spent.clear()
    _calls.clear()
    record_settings = RecordSettings(max_sim_time_s=max_sim_time, actuation_latency_ticks=latency)
    if course is not None and "course_detection" in RecordSettings.__dataclass_fields__:
        record_settings = dataclasses.replace(record_settings, course_detection=course)
    settings = RunSettings(record=record_settings)
    wall0, cpu0, child0 = time.perf_counter(), time.process_time(), _children_cpu()
    result = record.record(scenario, out, settings)
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    child = _children_cpu() - child0
    minutes = result.sim_duration_s / 60
    rendered = _calls["render"]
    print(
        f"{label}: {result.sim_duration_s:.1f} s sim, {scenario.camera.width}x"
        f"{scenario.camera.height} at {scenario.camera.rate_hz:g} Hz, {scenario.camera.encoding}, "
        f"mission {'done' if result.mission_done else 'not done'}, "
        f"markers {len(result.markers_found)}/{len(scenario.markers)}"
        + (
            f", worst error {max(result.marker_errors_m.values()) * 100:.2f} cm"
            if result.marker_errors_m
            else ""
        )
    )
    print(
        f"  real-time factor {result.sim_duration_s / wall:5.2f} (wall {wall:.1f} s), "
        f"{result.sim_duration_s / (cpu + child):5.2f} per CPU second (CPU {cpu:.1f} s in"
        f" usar, {child:.1f} s in the mission process), actuation latency {latency} tick(s)"
    )
    print(
        f"  log {result.size_bytes / 1e6:.2f} MB = {result.size_bytes / 1e6 / minutes:.2f} MB"
        f" per sim-minute; {result.frames} frames"
        + f", {rendered} rendered"
        + (f", {_calls['regions']} course-camera regions" if _calls["regions"] else "")
    )
    shown = {s: _spent.get(s, 0.0) for s in STAGES}
    rest = cpu - sum(shown.values())
    split = "  ".join(f"{s} {100 * v / cpu:4.1f}%" for s, v in shown.items())
    print(f"  usar's CPU: {split}  rest {100 * rest / cpu:4.1f}%")


def _camera_arg(text: str) -> tuple[int, int, float]:
    """``WxH@HZ`` -> (width, height, rate)."""
    try:
        size, hz = text.split("@")
        w, h = size.split("x")
        return int(w), int(h), float(hz)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not WxH@HZ (e.g. 1920x1080@30)") from None


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--course-seconds", type=float, default=120.0)
    ap.add_argument("--only", choices=("room", "course"))
    ap.add_argument("--encoding", choices=("png", "jpeg"), help="default: the scenario's")
    ap.add_argument("--keep", type=Path, help="write the logs into this directory and keep them")
    ap.add_argument("--latency", type=int, default=0, choices=(0, 1), help="actuation latency")
    ap.add_argument(
        "--camera", type=_camera_arg, help="WxH@HZ, e.g. 1920x1080@30; default: the scenario's"
    )
    ap.add_argument(
        "--course-detection",
        choices=("on", "off"),
        help="record.course_detection (issue 43); default: the recorder's",
    )
    args = ap.parse_args()
    course = None if args.course_detection is None else args.course_detection == "on"
    _instrument()

    def world(scn: Scenario) -> Scenario:
        cam = scn.camera
        if args.encoding is not None:
            cam = dataclasses.replace(cam, encoding=args.encoding)
        if args.camera is not None:
            w, h, hz = args.camera
            cam = dataclasses.replace(cam, width=w, height=h, rate_hz=hz)
        return dataclasses.replace(scn, camera=cam)

    with tempfile.TemporaryDirectory(prefix="usar-bench-") as scratch:
        tmp = args.keep or Path(scratch)
        if args.only in (None, "room"):
            bench(
                "one-room (whole mission)",
                world(one_room()),
                None,
                Path(tmp) / "room.mcap",
                args.latency,
                course,
            )
        if args.only in (None, "course"):
            bench(
                f"course (first {args.course_seconds:g} s)",
                world(course_world()),
                args.course_seconds,
                Path(tmp) / "course.mcap",
                args.latency,
                course,
            )


if __name__ == "__main__":
    main()
