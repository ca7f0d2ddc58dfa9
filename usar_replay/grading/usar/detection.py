"""Question 2, "markers detected": ``marker_k.detected``."""

from __future__ import annotations

from usar_replay.core import contract
from usar_replay.grading.usar.observations import NO_DETECTOR, Observations
from usar_replay.grading.usar.rules import RULES
from usar_replay.grading.usar.words import plural, sim_s
from usar_replay.grading.verdict import Check

__all__ = ["marker_detected"]


def marker_detected(g: Observations, mid: int) -> Check:
    """``marker_k.detected``: the detector reported ID k in a frame taken while the explorer
    was at a target (stopped or turning there, by the rubric's own radius), a detection the
    mission could use; a marker only glimpsed while driving past does not count. A ROS 1
    package reads its detections only where a node subscribes *and* a frame it broadcasts
    follows them (:meth:`.Observations.detections_followed`; issue 50)."""
    t = g.detected_ns.get(mid)
    frames = g.detected_frames.get(mid, 0)
    glimpsed = g.glimpsed_frames.get(mid, 0)
    each = 12.0 / max(len(g.markers), 1)
    if not g.fiducial_messages:
        measured = NO_DETECTOR
    elif g.detections_read is False:
        t = None  # seen by the course's detector, but nothing of the package read it
        seen = plural(frames, "frame")
        measured = f"no node subscribes to {contract.FIDUCIALS} (seen in {seen} at a target)"
    elif g.detections_read and t is not None and not g.detections_followed():
        t = None  # a node subscribes, but nothing it broadcast follows what it got (issue 50)
        seen = plural(frames, "frame")
        measured = (
            f"a node subscribes to {contract.FIDUCIALS}, but no frame it broadcast follows a "
            f"detection (seen in {seen} at a target)"
        )
    elif t is not None:
        measured = f"in {plural(frames, 'frame')} at a target, first at {sim_s(t)}"
    elif glimpsed:
        first = g.glimpsed_ns[mid]
        measured = (
            f"only glimpsed away from the targets ({plural(glimpsed, 'frame')}, first at "
            f"{sim_s(first)})"
        )
    else:
        measured = "never detected"
    return Check(
        id=f"marker_{mid}.detected",
        rule=RULES["detected"].text,
        description=f"explorer detected marker {mid} at a target",
        passed=t is not None,
        points=each if t is not None else 0.0,
        max_points=each,
        measured=measured,
        threshold=f"at least 1 frame on {contract.FIDUCIALS} within {g.target_radius:g} m of "
        "a target",
        evidence_ns=t if t is not None else g.glimpsed_ns.get(mid, g.detected_ns.get(mid)),
        value=float(frames),
        unit="frames",
        limit=1.0,
        op=">=",
        evidence="first detection"
        if t is not None
        else ("first glimpse" if mid in g.glimpsed_ns or mid in g.detected_ns else ""),
    )
