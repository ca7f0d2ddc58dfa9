"""Question 2, markers detected: a frame taken while the explorer was at a target."""

from __future__ import annotations

from rubric_streams import (
    EXPLORER_HOME,
    MARKERS,
    TARGETS,
    S,
    camera,
    detect,
    drive,
    send,
    world,
)

from usar_replay.core import contract
from usar_replay.grading.usar import (
    Grader,
    marker_detected,
)


def test_marker_detected_counts_frames() -> None:
    """Frames taken while the explorer was at a target count; a glimpse while driving past
    does not (a detection the mission could not use)."""
    g = Grader(world())
    drive(g, "explorer", [TARGETS[0]], 4 * S)
    detect(g, [0], 5 * S)
    detect(g, [0], 6 * S)
    seen, unseen = marker_detected(g, 0), marker_detected(g, 1)
    assert seen.passed and seen.value == 2 and seen.unit == "frames" and seen.evidence_ns == 5 * S
    assert seen.measured == "in 2 frames at a target, first at 5.0 s"
    assert not unseen.passed and unseen.value == 0 and unseen.evidence_ns is None
    assert unseen.measured == "never detected"
    past = Grader(world())
    drive(past, "explorer", [(3.0, 0.0)], 4 * S)  # between the targets
    detect(past, [1], 5 * S)
    glimpse = marker_detected(past, 1)
    assert not glimpse.passed and glimpse.evidence_ns == 5 * S
    assert glimpse.measured == "only glimpsed away from the targets (1 frame, first at 5.0 s)"


def test_without_the_detector_node_the_detection_lines_say_so() -> None:
    """No message at all on /fiducial_transforms (no ArucoDetect() in main()): every
    detection line fails and asks whether the detector node was started; an empty detection
    (the detector ran and saw nothing) is "never detected"."""
    g = Grader(world())
    drive(g, "explorer", [EXPLORER_HOME, TARGETS[0]], S)
    for mid in MARKERS:
        line = marker_detected(g, mid)
        assert not line.passed and line.points == 0
        assert line.measured == (
            "no /fiducial_transforms in the log: did the mission start the detector node "
            "(ArucoDetect)?"
        )
    detect(g, [], 3 * S)
    assert marker_detected(g, 0).measured == "never detected"


def test_a_package_that_reads_no_detections_detected_nothing() -> None:
    """The course's detector saw the marker at the target, but no node of the package
    subscribes to /fiducial_transforms (the log's ros1.toml says so): no detection of its."""
    g = Grader(world())
    drive(g, "explorer", [TARGETS[0]], 4 * S)
    detect(g, [0], 5 * S)
    assert marker_detected(g, 0).passed  # a Python mission, or an older log: not known
    g.detections_read = False
    line = marker_detected(g, 0)
    assert not line.passed and line.points == 0
    assert line.measured == (
        "no node subscribes to /fiducial_transforms (seen in 1 frame at a target)"
    )


def test_a_package_reads_its_detections_only_where_a_frame_follows_them() -> None:
    """Issue 50: a node that only subscribes to /fiducial_transforms (nothing broadcast), or
    whose only frame is a timer's sent whatever was detected, read nothing; a frame sent on the
    detection (a copy) says the package read it."""
    g = Grader(world())
    g.detections_read = True
    drive(g, "explorer", [TARGETS[0]], 4 * S)
    camera(g, 5 * S)
    detect(g, [0], 5 * S)
    line = marker_detected(g, 0)
    assert not line.passed and line.measured == (
        "a node subscribes to /fiducial_transforms, but no frame it broadcast follows a "
        "detection (seen in 1 frame at a target)"
    )
    for k in range(20):  # a timer's frame, every 0.5 s, detection or not
        camera(g, 5 * S + k * S // 2)
        send(g, "timer", (5.0, 5.0, 0.0), 5 * S + k * S // 2, parent=contract.MAP)
    assert not marker_detected(g, 0).passed
    send(g, contract.MARKER_FRAME, MARKERS[0], 5 * S)
    assert marker_detected(g, 0).passed
