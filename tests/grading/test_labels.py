"""The report's map and detection frames, as a person sees them: numbered evidence circles that
neither cover each other nor cross the frame, and a detected marker outlined where the detector
saw it (with a zoomed inset when it is small)."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

from usar_replay.core import contract, msgs
from usar_replay.grading.grade import grade_file
from usar_replay.grading.htmlreport import Detection, collect, detection_figure, draw_map
from usar_replay.grading.labels import Label, diameter_pt, place
from usar_replay.log.run import open_run
from usar_replay.pipeline.record import RecordResult
from usar_replay.world.detect import detect_with_corners


def _apart(labels: list[Label]) -> list[tuple[str, str, float]]:
    """Pairs of circles closer than their radii add up to (overlapping)."""
    return [
        (a.text, b.text, math.dist(a.center, b.center))
        for a, b in itertools.combinations(labels, 2)
        if math.dist(a.center, b.center) < a.radius + b.radius - 1e-9
    ]


def test_circles_on_one_spot_move_apart_and_stay_inside() -> None:
    """The course's start: many lines evidenced within centimetres of each other."""
    bounds = (0.0, 10.0, 0.0, 6.0)
    wanted = [(f"{n},{n + 1}", (0.3 + 0.01 * n, 0.2), 0.15) for n in range(1, 20, 2)]
    labels = place(wanted, bounds, gap=0.02)
    assert not _apart(labels)
    for lab in labels:
        assert bounds[0] + lab.radius <= lab.center[0] <= bounds[1] - lab.radius
        assert bounds[2] + lab.radius <= lab.center[1] <= bounds[3] - lab.radius
    assert labels[0].center == labels[0].anchor  # the first keeps its place
    assert sum(lab.moved for lab in labels) == len(labels) - 1


def test_a_circle_holds_its_text() -> None:
    assert diameter_pt("19,20", 7) > diameter_pt("7", 7) >= 7
    assert diameter_pt("19,20", 7) >= 0.6 * 7 * 5  # five characters of about 0.6 em


def test_the_maps_circles_do_not_overlap(room_log: tuple[Path, RecordResult]) -> None:
    """On the one-room run, lines 1 and 2,3 have their evidence 10 cm apart (at the target):
    the circles drawn there used to overlap."""
    path = room_log[0]
    run = open_run(path)
    fig, labels = draw_map(run.require_scenario(), grade_file(path), collect(run))
    assert len(labels) >= 4
    assert not _apart(labels), _apart(labels)
    assert any(lab.moved for lab in labels)
    (ax,) = fig.axes
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    for lab in labels:
        assert x0 <= lab.center[0] - lab.radius and lab.center[0] + lab.radius <= x1
        assert y0 <= lab.center[1] - lab.radius and lab.center[1] + lab.radius <= y1


def test_the_outline_lands_on_the_detected_corners(room_log: tuple[Path, RecordResult]) -> None:
    """The outline (the published pose through K) against the detector run again on the same
    recorded frame: within 1.5 px at every corner."""
    run = open_run(room_log[0])
    (det,) = collect(run).detections
    info = next(
        m.msg for m in run.messages([contract.CAMERA_INFO]) if isinstance(m.msg, msgs.CameraInfo)
    )
    image = msgs.CompressedImage(format=det.image_format, data=det.image)
    _, corners = detect_with_corners(image, info, run.settings.detector)
    assert len(det.corners) == 4 and det.size == (info.width, info.height)
    for (u, v), (cu, cv) in zip(det.corners, corners[det.marker_id], strict=True):
        assert math.dist((u, v), (float(cu), float(cv))) < 1.5


def test_a_far_marker_gets_a_zoomed_inset() -> None:
    near = Detection(
        3, 5_000_000_000, "png", b"x", ((100, 100), (300, 100), (300, 300), (100, 300)), (640, 480)
    )
    far = Detection(
        3, 5_000_000_000, "png", b"x", ((400, 200), (410, 200), (410, 210), (400, 210)), (640, 480)
    )
    assert "marker 3 (zoom)" not in detection_figure(near)
    html = detection_figure(far)
    assert html.count("<polygon") == 2 and "marker 3 (zoom)" in html
    assert "10 px wide" in html
    unknown = Detection(3, 5_000_000_000, "png", b"x")
    assert "<polygon" not in detection_figure(unknown) and "<img" in detection_figure(unknown)
