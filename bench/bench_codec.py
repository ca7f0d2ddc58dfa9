"""The camera codec, measured: PNG levels and JPEG qualities (printed, never asserted).

    python bench/bench_codec.py [--renderer auto|tiny|egl] [--frames N]

Two frame sets, both rendered in the course world with the recorder's renderer:

* **scenes**: the explorer's view from each lookup target, turned through a full circle, and
  from points between the targets (what a run mostly records): encode ms, decode ms and bytes
  per frame, medians, and MB per sim-minute at the camera's rate (every frame distinct, i.e. an
  upper bound: frames repeated while nothing moves cost almost nothing after zstd).
* **markers**: each course marker seen from its target at several angles across the view. The
  detector runs on the decoded frame; its marker position is taken to map with the true camera
  pose and compared with the true marker position. ``err`` is the worst single-frame error and
  ``vs png`` the worst change against the lossless frame's detection (what the codec alone adds;
  the mission stores the median of 5 frames, so its error is lower still).
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
from collections.abc import Callable
from itertools import pairwise

import cv2
import numpy as np

from usar_replay.core import msgs
from usar_replay.sim.camera import encode_image
from usar_replay.sim.simulator import Simulator
from usar_replay.world.detect import DetectorParams, decode_image, detect
from usar_replay.world.scenario import course_world

TARGET_MARKER = {0: 0, 1: 1, 2: 3, 3: 2}
"""The marker each course target sees (course-world.md)."""
CODECS: tuple[tuple[str, int], ...] = (
    ("png", 1),
    ("png", 3),
    ("png", 6),
    ("png", 9),
    ("jpeg", 60),
    ("jpeg", 70),
    ("jpeg", 75),
    ("jpeg", 80),
    ("jpeg", 85),
    ("jpeg", 90),
    ("jpeg", 95),
)


def _encoder(fmt: str, level: int) -> Callable[[np.ndarray], bytes]:
    if fmt == "png":
        return lambda img: encode_image(img, "png", png_level=level)
    return lambda img: encode_image(img, "jpeg", jpeg_quality=level)


def _frames(renderer: str, n_scene: int) -> tuple[list[np.ndarray], list[tuple], str]:
    scn = course_world()
    scenes: list[np.ndarray] = []
    markers: list[tuple] = []
    with Simulator(scn, renderer=renderer) as sim:
        targets = list(scn.targets)
        between = [((ax + bx) / 2, (ay + by) / 2) for (ax, ay), (bx, by) in pairwise(targets)]
        stops = targets + between
        per_stop = max(1, n_scene // len(stops))
        for x, y in stops:
            for i in range(per_stop):
                sim.teleport("explorer", x, y, 2 * math.pi * i / per_stop)
                scenes.append(sim.render_camera())
        info = sim.camera_info()
        for k, (tx, ty) in enumerate(scn.targets):
            m = scn.marker_by_id(TARGET_MARKER[k])
            for off in (-0.45, -0.3, -0.15, 0.0, 0.15, 0.3, 0.45):
                sim.teleport("explorer", tx, ty, math.atan2(m.y - ty, m.x - tx) + off)
                eye, rot = sim.camera_pose()
                markers.append((sim.render_camera(), info, eye, rot, m))
        return scenes, markers, sim.renderer_name


def _map_error(
    data: bytes, fmt: str, info: msgs.CameraInfo, eye: np.ndarray, rot: np.ndarray, m: object
) -> tuple[float, np.ndarray] | None:
    image = msgs.CompressedImage(header=info.header, format=fmt, data=data)
    found = [f for f in detect(image, info, DetectorParams()).transforms]
    hits = [f for f in found if f.fiducial_id == m.id]  # type: ignore[attr-defined]
    if not hits:
        return None
    t = hits[0].transform.translation
    in_map = eye + rot @ np.array([t.x, t.y, t.z])
    truth = (m.x, m.y, m.z)  # type: ignore[attr-defined]
    return math.dist(in_map, truth), in_map


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--renderer", default="auto")
    ap.add_argument("--frames", type=int, default=42, help="scene frames (default 42)")
    args = ap.parse_args()
    scenes, markers, renderer = _frames(args.renderer, args.frames)
    rate = course_world().camera.rate_hz
    print(
        f"OpenCV {cv2.__version__}, renderer {renderer}, {scenes[0].shape[1]}x"
        f"{scenes[0].shape[0]}, {len(scenes)} scene frames, {len(markers)} marker frames"
    )
    lossless = [
        _map_error(encode_image(img, "png"), "png", info, eye, rot, m)
        for img, info, eye, rot, m in markers
    ]
    print("codec     encode ms  decode ms  KB/frame  MB/sim-min  found   err cm  vs png cm")
    for fmt, level in CODECS:
        enc = _encoder(fmt, level)
        t_enc, t_dec, sizes = [], [], []
        for img in scenes:
            t0 = time.process_time()
            data = enc(img)
            t1 = time.process_time()
            decode_image(data)
            t2 = time.process_time()
            t_enc.append(t1 - t0)
            t_dec.append(t2 - t1)
            sizes.append(len(data))
        found, worst, drift = 0, 0.0, 0.0
        for (img, info, eye, rot, m), ref in zip(markers, lossless, strict=True):
            got = _map_error(enc(img), fmt, info, eye, rot, m)
            if got is None:
                continue
            found += 1
            worst = max(worst, got[0])
            if ref is not None:
                drift = max(drift, float(np.linalg.norm(got[1] - ref[1])))
        kb = statistics.median(sizes) / 1e3
        print(
            f"{fmt + ' ' + str(level):<9} {statistics.median(t_enc) * 1e3:9.2f}"
            f"  {statistics.median(t_dec) * 1e3:9.2f}  {kb:8.1f}  {kb * rate * 60 / 1e3:10.2f}"
            f"  {found:2d}/{len(markers):<2d}  {worst * 100:7.2f}  {drift * 100:9.2f}"
        )


if __name__ == "__main__":
    main()
