"""Detector settings against OpenCV's defaults on recorded frames (printed, never asserted).

Why: the mission's detector decodes frames to grey and thresholds at fewer window sizes than
OpenCV's default, to be faster. This checks that it still finds what the reference finds
(colour decode, OpenCV's default thresholds, the same corner refinement): per variant, CPU
time per frame, markers within 2.5 m (the mission's detection range) the reference found and
the variant missed, detections the reference did not make, and how far each marker's
position (IPPE_SQUARE pose from the four corners) moved from the reference's.

The frames: every second frame whose recorded ``/fiducial_transforms`` has a marker within
3 m (the frames the mission acts on).

Usage::

    python bench/bench_detect.py LOG.mcap [LOG.mcap ...]
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import time
from pathlib import Path

import cv2
import numpy as np

from usar_replay.core import cdr, contract, msgs
from usar_replay.log.run import open_run
from usar_replay.world.detect import _REFINE, DetectorParams, _object_points


@dataclasses.dataclass
class _Stats:
    missed: int = 0
    extra: int = 0
    cpu: float = 0.0
    moved: list[float] = dataclasses.field(default_factory=list)


def _detector(params: DetectorParams, step: int | None) -> cv2.aruco.ArucoDetector:
    dictionary = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, params.dictionary))
    p = cv2.aruco.DetectorParameters()
    p.cornerRefinementMethod = _REFINE[params.corner_refinement]
    if step is not None:
        p.adaptiveThreshWinSizeStep = step
    return cv2.aruco.ArucoDetector(dictionary, p)


def _positions(
    det: cv2.aruco.ArucoDetector, img: np.ndarray, k: np.ndarray, size: float
) -> dict[int, np.ndarray]:
    corners, ids, _ = det.detectMarkers(img)
    out: dict[int, np.ndarray] = {}
    if ids is None:
        return out
    for mid, c in zip(np.asarray(ids).ravel().tolist(), corners, strict=True):
        pts = np.asarray(c, dtype=np.float64).reshape(4, 2)
        _, _, tvec = cv2.solvePnP(
            _object_points(size), pts, k, None, flags=cv2.SOLVEPNP_IPPE_SQUARE
        )
        out[int(mid)] = tvec.ravel()
    return out


def _frames(path: Path) -> tuple[np.ndarray, list[bytes]]:
    run = open_run(path)
    k: np.ndarray | None = None
    images: dict[int, bytes] = {}
    wanted: list[int] = []
    for m in run.messages(decode=False):
        if m.topic == contract.CAMERA_INFO and k is None:
            info = cdr.decode(m.data, m.msgtype)
            assert isinstance(info, msgs.CameraInfo)
            k = np.array(info.k, dtype=np.float64).reshape(3, 3)
        elif m.topic == contract.IMAGE:
            image = cdr.decode(m.data, m.msgtype)
            assert isinstance(image, msgs.CompressedImage)
            images[image.header.stamp.ns] = bytes(image.data)
        elif m.topic == contract.FIDUCIALS:
            found = cdr.decode(m.data, m.msgtype)
            assert isinstance(found, msgs.FiducialTransformArray)
            near = any(
                math.dist((0, 0, 0), (t.x, t.y, t.z)) < 3.0
                for t in (f.transform.translation for f in found.transforms)
            )
            if near:
                wanted.append(found.header.stamp.ns)
    if k is None:
        raise SystemExit(f"{path}: no camera info")
    return k, [images[t] for t in wanted[::2] if t in images]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("logs", nargs="+", type=Path)
    args = parser.parse_args()
    cv2.setNumThreads(1)  # as in the mission process
    params = DetectorParams()
    reference = _detector(params, None)
    variants = {
        "grey, OpenCV thresholds": _detector(params, None),
        f"grey, window step {params.threshold_window_step} (default)": _detector(
            params, params.threshold_window_step
        ),
        "grey, one window (3)": _detector(params, 100),
    }
    stats = {name: _Stats() for name in variants}
    frames = 0
    for path in args.logs:
        k, datas = _frames(path)
        frames += len(datas)
        for data in datas:
            arr = np.frombuffer(data, dtype=np.uint8)
            ref = _positions(reference, cv2.imdecode(arr, cv2.IMREAD_COLOR), k, params.marker_size)
            grey = cv2.imdecode(arr, cv2.IMREAD_GRAYSCALE)
            for name, det in variants.items():
                s = stats[name]
                t = time.process_time()
                got = _positions(det, grey, k, params.marker_size)
                s.cpu += time.process_time() - t
                for mid, pos in ref.items():
                    if np.linalg.norm(pos) > 2.5:
                        continue
                    if mid not in got:
                        s.missed += 1
                    else:
                        s.moved.append(float(np.linalg.norm(pos - got[mid])))
                s.extra += sum(1 for mid in got if mid not in ref)
    print(f"{frames} frames with a marker within 3 m, from {len(args.logs)} log(s)")
    for name, s in stats.items():
        moved = np.array(s.moved or [0.0]) * 100
        print(
            f"{name:34s} {s.cpu / max(frames, 1) * 1e3:5.2f} ms/frame; missed {s.missed}, "
            f"extra {s.extra}; moved median {np.median(moved):.3f} cm, "
            f"p99 {np.percentile(moved, 99):.3f} cm, max {moved.max():.3f} cm"
        )


if __name__ == "__main__":
    main()
