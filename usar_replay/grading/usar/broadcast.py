"""Question 3, "properly broadcast? We will take a look at the frames in RViz":
``marker_k.broadcast`` and ``marker_frame.only_on_detection``.

A marker's frames are placed as a TA sees them (:func:`frame_places`): each frame at the median
of its broadcasts made while the explorer scanned at a target; the worst frame decides (a
shotgun earns nothing), a stand-off frame alone earns half, where it follows the detections
(:mod:`.follow`: on the camera's line to the marker, or at one offset from the detected pose);
a frame that stays put in the camera frame while the detections move ignores them: it earns
nothing, and its broadcasts are not "on a detection" (issue 50).
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Sequence
from dataclasses import dataclass

from usar_replay.core import contract
from usar_replay.grading.usar.observations import FrameBroadcasts, Observations
from usar_replay.grading.usar.rules import RULES, STEADY
from usar_replay.grading.usar.words import plural
from usar_replay.grading.verdict import Check

__all__ = [
    "FramePlace",
    "frame_places",
    "marker_broadcast",
    "only_on_detection",
    "place_text",
    "shown_place",
]


@dataclass(frozen=True, slots=True)
class FramePlace:
    """One frame's place as a TA judges it: the median of its deciding broadcasts."""

    frame: FrameBroadcasts
    place: tuple[float, float, float]
    error_m: float
    kind: str
    """``on`` (within the threshold of the marker), ``stand-off`` (in front of the marker's
    face, within the follower's stand-off: a goal frame, half the points) or ``off``."""
    broadcasts: int
    where: str
    """``at a target`` or ``anywhere`` (no frame of the marker was broadcast at a target)."""
    follow: str = "unknown"
    """How the frame follows the detections (:meth:`.Observations.frame_verdict`)."""


def _median(points: Sequence[tuple[float, ...]]) -> tuple[float, ...]:
    """The component-wise median (a few wild broadcasts do not move it)."""
    return tuple(statistics.median(p[i] for p in points) for i in range(len(points[0])))


def frame_places(g: Observations, mid: int) -> list[FramePlace]:
    """Each frame broadcast for marker ``mid``, placed as a TA sees it in RViz: the median of
    its broadcasts while the explorer was at a target, of detections within the reliable range
    (when no frame of the marker was broadcast so, the median of all its broadcasts); a frame
    never found in ``map`` is ``off`` with an infinite error. By frame name.

    Only the frames broadcast *as detections* are judged where the marker has some: a frame
    sent mostly without a detection (a timer's, the course template's dummy ``my_frame`` left
    in, as rpatil10's package has it) is no frame of the marker's, so it cannot be its worst
    (``only_on_detection`` judges it); where a marker has no other, it is judged alone (a stored
    pose sent again, which "follows the robot around", fails there)."""
    frames = sorted(g.broadcasts[mid].frames.values(), key=lambda f: f.frame)
    of_detections = [f for f in frames if _of_detections(g, f.frame)]
    frames = of_detections or frames
    at_target = any(f.at_target for f in frames)
    marker = g.markers[mid]
    out: list[FramePlace] = []
    for f in frames:
        follow = g.frame_verdict(f.frame)
        ring = f.at_target if at_target else f.elsewhere
        n = f.at_target_count if at_target else f.elsewhere_count
        where = "at a target" if at_target else "anywhere"
        if not ring:
            if f.failed_lookups and not (at_target and f.elsewhere):
                out.append(
                    FramePlace(f, (math.inf,) * 3, math.inf, "off", f.count, where, follow)
                )
            continue
        place = _median([p for p, _ in ring])
        seen_from = _median([e for _, e in ring])
        err = math.dist(place, marker)
        limit = g.th.marker_map_error_m
        on = sum(math.dist(p, marker) <= limit for p, _ in ring) >= STEADY * len(ring)
        steady = sum(math.dist(p, place) <= limit for p, _ in ring) >= STEADY * len(ring)
        if follow == "ignores":
            kind = "off"  # wherever it shows, it is no detection's (issue 50)
        elif err <= limit and on:
            kind = "on"
        elif steady and follow == "follows" and _stand_off(g, mid, place, seen_from):
            kind = "stand-off"
        else:
            kind = "off"
        out.append(FramePlace(f, (place[0], place[1], place[2]), err, kind, n, where, follow))
    return out


def _of_detections(g: Observations, frame: str) -> bool:
    """Were most of ``frame``'s broadcasts made on a detection?"""
    with_one, without = g.frame_tally.get(frame, [0, 0])
    return with_one >= without


def _stand_off(
    g: Observations, mid: int, place: tuple[float, ...], seen_from: tuple[float, ...]
) -> bool:
    """A frame put deliberately in front of the marker: on its face's side, towards the camera,
    no farther than the follower's stand-off (0.4 m in x and in y) plus the threshold. (Only
    asked of a frame that follows the detections: a place alone is no stand-off.)"""
    x, y, _z = g.markers[mid]
    yaw = g.marker_yaw.get(mid, 0.0)
    vx, vy = place[0] - x, place[1] - y
    ahead = vx * math.cos(yaw) + vy * math.sin(yaw)
    cx, cy = seen_from[0] - x, seen_from[1] - y
    # between the marker and the camera: within 45 degrees of the way to the camera (an
    # offset sideways, along the image's x, is a wrong frame, not a goal in front of it)
    apart = math.hypot(vx, vy)
    camera_side = cx * vx + cy * vy > math.cos(math.pi / 4) * math.hypot(cx, cy) * apart
    within = apart <= g.stand_off_m
    return ahead > 0.0 and camera_side and within


def shown_place(places: Sequence[FramePlace]) -> FramePlace:
    """The frame the line shows: the worst ``off`` one (it decides), else the most broadcast
    ``on`` one, else the most broadcast stand-off."""
    off = [p for p in places if p.kind == "off"]
    if off:
        return max(off, key=lambda p: (p.error_m, p.frame.frame))
    rank = {"on": 0, "stand-off": 1}
    return min(places, key=lambda p: (rank[p.kind], -p.broadcasts, p.frame.frame))


def place_text(places: Sequence[FramePlace], shown: FramePlace) -> str:
    """What a marker's broadcasts measured, in words (the line's and the record summary's)."""
    others = len(places) - 1
    also = f" (worst of {len(places)} frames)" if shown.kind == "off" and others else (
        f" (and {plural(others, 'other frame')})" if others else ""
    )
    head = f"{shown.frame.frame}: median of {plural(shown.broadcasts, 'broadcast')} {shown.where}"
    if not math.isfinite(shown.error_m):
        return f"{shown.frame.frame}: not found in {contract.MAP} or not finite{also}"
    text = f"{head}, {shown.error_m * 100:.1f} cm from the marker"
    if shown.follow == "ignores":
        text += ": it stays put in the camera frame whatever was detected (it ignores them)"
    elif shown.kind == "stand-off":
        text += ": a stand-off frame in front of it (half the points)"
    return text + also


def _stamps_text(frame: str, stamps: tuple[int, int]) -> str:
    """``my_frame stamped 12.350 s, image 12.300 s``: which broadcast a line used."""
    return f"{frame} stamped {stamps[0] / 1e9:.3f} s, image {stamps[1] / 1e9:.3f} s"


def marker_broadcast(g: Observations, mid: int) -> Check:
    """``marker_k.broadcast``: the frames broadcast on ``/tf`` (any name) as detections of
    marker k, each placed as a TA sees it in RViz (:func:`frame_places`): every frame on the
    marker passes; a stand-off frame alone earns half; one frame off the marker fails the line
    (several frames for one detection are judged by the worst: a shotgun earns nothing)."""
    places = frame_places(g, mid)
    limit = g.th.marker_map_error_m
    each = 8.0 / max(len(g.markers), 1)
    recent = f"{g.th.detection_recent_s:g} s"
    if not places:
        measured = (
            "nothing broadcast on /tf"
            if g.broadcast_count == 0
            else f"no broadcast within {recent} after a detection of marker {mid}"
        )
        shown = None
        points = 0.0
    else:
        shown = shown_place(places)
        measured = place_text(places, shown)
        points = {"on": each, "stand-off": each / 2, "off": 0.0}[shown.kind]
    ok = shown is not None and shown.kind == "on"
    if shown is None:
        evidence_ns, evidence = None, ""
    elif shown.kind == "off":
        f = shown.frame
        evidence_ns, evidence = f.worst_ns, "worst broadcast: " + _stamps_text(
            f.frame, f.worst_stamp
        )
    else:
        f = shown.frame
        evidence_ns, evidence = f.first_ns, "first broadcast: " + _stamps_text(
            f.frame, f.first_stamp
        )
    return Check(
        id=f"marker_{mid}.broadcast",
        rule=RULES["broadcast"].text,
        description=f"marker {mid} broadcast on /tf (any frame name), where it is",
        passed=ok,
        points=points,
        max_points=each,
        measured=measured,
        threshold=f"median at a target within {limit * 100:g} cm, each frame (a stand-off "
        "frame: half)",
        evidence_ns=evidence_ns,
        value=shown.error_m if shown is not None and math.isfinite(shown.error_m) else None,
        unit="m",
        limit=limit,
        op="<=",
        evidence=evidence,
    )


def only_on_detection(g: Observations) -> Check:
    """``marker_frame.only_on_detection``: no broadcast without a detection or off the camera.

    Every frame broadcast on ``/tf`` that is not the simulator's counts (whatever its name).
    One is without a detection when no non-empty detection came within ``detection_recent_s``
    before it, or when the latest ``/fiducial_transforms`` was empty (the marker out of view)
    and it is not a detection's first broadcast (a stored pose sent again). A queued detection
    drained late by a slow loop is a detection's. A line that judges
    broadcasts gives no credit when there were none: a mission that never broadcast (it
    crashed at its first target, or has no broadcaster yet) has shown nothing this line can
    judge, so it fails with "nothing broadcast" rather than passing by default."""
    ignoring = g.ignoring_frames()
    ignored = sum(g.frame_tally.get(f, [0, 0])[0] for f in ignoring)
    bad = g.bad_broadcasts + ignored
    firsts = [
        (t, what)
        for t, what in (
            (g.without_detection_ns, g.without_detection_what),
            (g.wrong_parent_ns, g.wrong_parent_what),
        )
        if t is not None
    ]
    for b in g.broadcasts.values():  # an ignoring frame's first broadcast is a bad one too
        for name in ignoring:
            f = b.frames.get(name)
            if f is not None and f.first_ns is not None:
                firsts.append((f.first_ns, f"{name} stamped {f.first_stamp[0] / 1e9:.3f} s"))
    first_bad = min(firsts, default=None)
    ok = bad == 0 and g.broadcast_count > 0
    period = f"{g.th.detection_recent_s:g} s"
    if g.broadcast_count == 0:
        measured = "nothing broadcast on /tf"
    else:
        names = ", ".join(list(g.broadcast_frames)[:3])
        if len(g.broadcast_frames) > 3:
            names += f" and {len(g.broadcast_frames) - 3} more"
        measured = (
            f"{plural(g.broadcast_count, 'broadcast')} ({names}), {g.without_detection} without "
            f"a detection within {period}, {g.wrong_parent} with another parent"
        )
        if ignored:
            which = ", ".join(ignoring[:2]) + (" ..." if len(ignoring) > 2 else "")
            measured += f", {ignored} ignoring the detection ({which})"
    return Check(
        id="marker_frame.only_on_detection",
        rule=RULES["only_on_detection"].text,
        description="frames broadcast only with a detection, child of the camera",
        passed=ok,
        points=4.0 if ok else 0.0,
        max_points=4.0,
        measured=measured,
        threshold=f"0 without a detection in the {period} before; parent "
        f"{contract.OPTICAL_FRAME}",
        evidence_ns=None if first_bad is None else first_bad[0],
        value=float(bad) if g.broadcast_count else None,  # nothing broadcast: nothing measured
        unit="broadcasts",
        limit=0.0,
        op="<=",
        evidence="" if first_bad is None else f"first bad broadcast: {first_bad[1]}",
    )
