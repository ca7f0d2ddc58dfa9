"""Question 3, properly broadcast: the frames as a TA sees them in RViz, and only on a
detection."""

from __future__ import annotations

import math
from typing import Any

import pytest
from rubric_streams import (
    EXPLORER_HOME,
    MARKERS,
    MS,
    TARGETS,
    S,
    broadcast,
    camera,
    detect,
    drive,
    empty,
    judge_failed,
    send,
    world,
)

from usar_replay.core import contract, msgs
from usar_replay.core.settings import Thresholds
from usar_replay.grading.usar import (
    MAX_FRAMES,
    Grader,
    marker_broadcast,
    only_on_detection,
)


def test_marker_broadcast_is_the_median_at_the_target() -> None:
    """As a TA sees the frame in RViz while the explorer is at the target: the median of the
    broadcasts there (one wild one does not move it); those made while driving do not decide;
    a frame that stays 0.3 m off fails, with its worst broadcast as evidence."""
    g = Grader(world())
    drive(g, "explorer", [TARGETS[0]], 4 * S)
    for t, err in ((5 * S, 0.02), (6 * S, 0.03), (7 * S, 0.3)):
        detect(g, [0], t)
        broadcast(g, 0, t, error_m=err)
    drive(g, "explorer", [(3.0, 0.0)], 8 * S)  # driving: a bad broadcast does not decide
    detect(g, [0], 9 * S)
    broadcast(g, 0, 9 * S, error_m=0.5)
    line = marker_broadcast(g, 0)
    assert line.passed and line.value == pytest.approx(0.03) and line.limit == 0.10
    assert line.measured == (
        "marker_frame: median of 3 broadcasts at a target, 3.0 cm from the marker"
    )
    assert line.evidence == "first broadcast: marker_frame stamped 5.000 s, image 5.000 s"
    none = marker_broadcast(g, 1)
    assert none.measured == "no broadcast within 2 s after a detection of marker 1"
    assert none.value is None and none.evidence_ns is None
    off = Grader(world())
    drive(off, "explorer", [TARGETS[0]], 4 * S)
    for t in (5 * S, 6 * S):
        detect(off, [0], t)
        broadcast(off, 0, t, error_m=0.3)
    bad = marker_broadcast(off, 0)
    assert not bad.passed and bad.value == pytest.approx(0.3) and bad.evidence_ns == 5 * S
    assert bad.evidence == "worst broadcast: marker_frame stamped 5.000 s, image 5.000 s"
    loose = Grader(world(), Thresholds(marker_map_error_m=0.5))
    detect(loose, [0], 5 * S)
    broadcast(loose, 0, 5 * S, error_m=0.3)
    assert marker_broadcast(loose, 0).passed


def test_only_on_detection_counts_broadcasts_without_one_or_off_the_camera() -> None:
    g = Grader(world())
    detect(g, [0], 5 * S)
    broadcast(g, 0, 5 * S)
    assert only_on_detection(g).passed and only_on_detection(g).evidence_ns is None
    broadcast(g, 0, 8 * S)  # the last detection came 3 s before
    broadcast(g, 0, 9 * S, parent=contract.MAP)
    line = only_on_detection(g)
    assert not line.passed and line.value == 2 and line.limit == 0
    assert line.measured == (
        "3 broadcasts (marker_frame), 2 without a detection within 2 s, 1 with another parent"
    )
    assert line.evidence_ns == 8 * S
    assert line.evidence == "first bad broadcast: marker_frame stamped 8.000 s"


def test_a_queued_detection_drained_late_is_a_detection() -> None:
    """A slow loop drains a subscriber queue of 1000: each detection is broadcast once, 0.2 to
    1.1 s after it came, stamped now, while the detector already sees nothing: no violation."""
    g = Grader(world())
    for k in range(3):
        detect(g, [0], 5 * S + k * 100 * MS)
    empty(g, 5 * S + 300 * MS)
    for k, late in enumerate((200 * MS, 600 * MS, 1100 * MS)):
        broadcast(g, 0, 5 * S + k * 100 * MS + late)
    line = only_on_detection(g)
    assert line.passed, line.measured


def test_a_stored_pose_sent_again_after_an_empty_detection_is_not_one() -> None:
    """The handout's rule, "broadcast only when the marker is detected": a package that sends
    its stored detection again on every callback, also when the detection is empty."""
    g = Grader(world())
    detect(g, [0], 5 * S)
    broadcast(g, 0, 5 * S)
    empty(g, 5 * S + 100 * MS)
    broadcast(g, 0, 5 * S + 100 * MS)  # the same detection again, nothing in view
    line = only_on_detection(g)
    assert not line.passed and line.evidence_ns == 5 * S + 100 * MS
    assert line.measured == (
        "2 broadcasts (marker_frame), 1 without a detection within 2 s, 0 with another parent"
    )


def test_only_on_detection_gives_no_credit_when_nothing_was_broadcast() -> None:
    """A run that never broadcast (a mission that crashed at its first target) has shown
    nothing this line judges: it fails, measured "nothing broadcast", with no points."""
    g = Grader(world())
    drive(g, "explorer", [EXPLORER_HOME, TARGETS[0]], S)
    detect(g, [0], 3 * S)  # detected, but never broadcast
    line = only_on_detection(g)
    assert not line.passed and line.points == 0 and line.max_points == 4
    assert line.measured == "nothing broadcast on /tf"
    assert line.value is None and line.evidence_ns is None  # nothing measured
    assert "marker_frame.only_on_detection" in judge_failed(g)


def test_a_broadcast_of_any_name_late_counts() -> None:
    """okritvik's and the sample code's shape: ``my_frame`` stamped ``now()`` a tick (50 ms)
    or a whole camera period (100 ms) after the image; the line names the frame and stamps."""
    g = Grader(world())
    for t in (5 * S, 5 * S + 50 * MS, 5 * S + 100 * MS):
        camera(g, t)
    detect(g, [0], 5 * S)
    send(g, "my_frame", MARKERS[0], 5 * S + 50 * MS)
    send(g, "my_frame", MARKERS[0], 5 * S + 100 * MS)
    line = marker_broadcast(g, 0)
    assert line.passed
    assert line.measured == "my_frame: median of 2 broadcasts anywhere, 0.0 cm from the marker"
    assert line.evidence == "first broadcast: my_frame stamped 5.050 s, image 5.000 s"
    only = only_on_detection(g)
    assert only.passed, only.measured
    assert only.measured.startswith("2 broadcasts (my_frame), 0 without a detection")


def test_a_broadcast_long_after_the_last_detection_has_none() -> None:
    g = Grader(world())
    for t in (5 * S, 7 * S + 500 * MS):
        camera(g, t)
    detect(g, [0], 5 * S)
    send(g, "target_0", MARKERS[0], 7 * S + 500 * MS)
    line = marker_broadcast(g, 0)
    assert not line.passed
    assert line.measured == "no broadcast within 2 s after a detection of marker 0"
    only = only_on_detection(g)
    assert not only.passed and only.evidence_ns == 7 * S + 500 * MS
    assert only.evidence == "first bad broadcast: target_0 stamped 7.500 s"


def test_with_detections_a_tick_late_a_broadcast_counts_from_their_arrival() -> None:
    """``record.detection_latency_ticks`` 1 (a ROS 1 package's default): the image stamped
    5.0 s is answered at 5.05 s; a broadcast sent after that counts, one sent before the
    answer came has no detection."""
    g = Grader(world())
    for t in (5 * S, 5 * S + 10 * MS, 5 * S + 50 * MS, 5 * S + 150 * MS):
        camera(g, t)
    send(g, "marker_frame", MARKERS[0], 5 * S + 10 * MS)  # nothing detected yet
    detect(g, [0], 5 * S, came=5 * S + 50 * MS)
    send(g, "marker_frame", MARKERS[0], 5 * S + 150 * MS)
    line = marker_broadcast(g, 0)
    assert line.passed and line.evidence.endswith("stamped 5.150 s, image 5.000 s")
    only = only_on_detection(g)
    assert not only.passed and only.measured.startswith("2 broadcasts (marker_frame), 1 without")
    assert only.evidence_ns == 5 * S + 10 * MS


def test_a_zero_stamp_is_the_time_it_was_published() -> None:
    """``ros::Time(0)`` as a stamp: the frame as it stood when it was sent (tf's "latest")."""
    g = Grader(world())
    for t in (5 * S, 5 * S + 50 * MS):
        camera(g, t)
    detect(g, [0], 5 * S)
    send(g, "marker_frame", MARKERS[0], 5 * S + 50 * MS, stamp=0)
    assert marker_broadcast(g, 0).passed and only_on_detection(g).passed
    assert "stamped 5.050 s, image 5.000 s" in marker_broadcast(g, 0).evidence


def test_the_map_position_is_the_parent_chain_at_the_stamp() -> None:
    """The camera moved 0.4 m between the image and the late stamp: the frame, copied from the
    image's detection, is 0.4 m off where tf puts it then, and the line fails. A frame under
    map itself is judged by where it is (passes), and only_on_detection names its parent."""
    g = Grader(world())
    camera(g, 5 * S)
    camera(g, 5 * S + 50 * MS, x=0.4)
    detect(g, [0], 5 * S)
    send(g, "my_frame", MARKERS[0], 5 * S + 50 * MS)
    line = marker_broadcast(g, 0)
    assert not line.passed and line.value == pytest.approx(0.4)
    in_map = Grader(world())
    camera(in_map, 5 * S)
    detect(in_map, [1], 5 * S)
    send(in_map, "target_1", MARKERS[1], 5 * S + 50 * MS, parent=contract.MAP)
    assert marker_broadcast(in_map, 1).passed
    only = only_on_detection(in_map)
    assert not only.passed and "1 with another parent" in only.measured


def test_the_simulators_frames_are_not_broadcasts() -> None:
    g = Grader(world())
    camera(g, 5 * S)
    detect(g, [0], 5 * S)
    send(g, "explorer_tf/base_footprint", (0.0, 0.0, 0.0), 5 * S, parent="explorer_tf/odom")
    assert only_on_detection(g).measured == "nothing broadcast on /tf"
    assert marker_broadcast(g, 0).measured == "nothing broadcast on /tf"


def test_several_frames_for_one_detection_are_judged_by_the_worst() -> None:
    """A shotgun (frames along the camera's ray, one of them on the marker) earns nothing;
    one frame on the marker and a stand-off goal frame in front of it (the follower's goal,
    on the camera's line to the marker) pass; a stand-off frame alone earns half, and says so;
    0.4 m behind the marker's face is no stand-off (it fails)."""
    g = Grader(world())
    camera(g, 5 * S)
    detect(g, [0], 5 * S)
    x, y, z = MARKERS[0]
    for k in range(4):  # 0, 0.2, 0.4, 0.6 m short along the ray from the camera
        f = k * 0.2 / (x * x + y * y + z * z) ** 0.5
        send(g, f"ray_{k}", (x * (1 - f), y * (1 - f), z * (1 - f)), 5 * S)
    shot = marker_broadcast(g, 0)
    assert not shot.passed and shot.points == 0 and "(worst of 4 frames)" in shot.measured

    def one(*frames: tuple[str, tuple[float, float, float]]) -> Any:
        h = Grader(world())
        cam = (3.0, 1.0, z)  # in front of the marker's face (+x), looking at it
        send(h, contract.OPTICAL_FRAME, cam, 5 * S, parent=contract.MAP)
        drive(h, "explorer", [(3.0, 1.0)], 5 * S)
        detect(h, [0], 5 * S, at=cam)
        for name, (px, py, pz) in frames:
            send(h, name, (px - cam[0], py - cam[1], pz - cam[2]), 5 * S)
        return marker_broadcast(h, 0)

    front = (x + 0.45, y, z)
    both = one(("my_frame", MARKERS[0]), ("goal", front))
    assert both.passed and both.points == both.max_points, both.measured
    assert both.measured.startswith("my_frame: ") and "(and 1 other frame)" in both.measured
    alone = one(("goal", front))
    assert not alone.passed and alone.points == alone.max_points / 2
    assert "a stand-off frame in front of it (half the points)" in alone.measured
    behind = one(("goal", (x - 0.4, y, z)))
    assert not behind.passed and behind.points == 0


def test_frame_names_are_escaped_shortened_and_bounded() -> None:
    """The team's frame names reach a TA's terminal: escaped, at most 40 characters, and a
    new name every tick costs no memory past MAX_FRAMES."""
    g = Grader(world())
    camera(g, 5 * S)
    detect(g, [0], 5 * S)
    send(g, "\x1b[2J" + "x" * 100, MARKERS[0], 5 * S)
    line = marker_broadcast(g, 0)
    assert line.passed and line.measured.startswith("\\x1b[2J" + "x" * 30 + "...: median of")
    for k in range(MAX_FRAMES + 5):
        send(g, f"f{k}", MARKERS[0], 5 * S)
    assert len(g.broadcast_frames) == MAX_FRAMES + 1  # the first 16 names, then "(other frames)"
    assert " and 14 more)" in only_on_detection(g).measured


def test_tf_keeps_the_last_broadcast_at_a_stamp() -> None:
    """Team 001's bug: the right frame, then an identity one at the same stamp; tf (and RViz)
    keeps the last one inserted at a stamp, so the frame a TA sees is at the camera: fails."""
    g = Grader(world())
    drive(g, "explorer", [TARGETS[0]], 4 * S)
    for t in (5 * S, 6 * S, 7 * S):
        camera(g, t)
        detect(g, [0], t)
        send(g, contract.MARKER_FRAME, MARKERS[0], t)
        send(g, contract.MARKER_FRAME, (0.0, 0.0, 0.0), t)  # "broadcast() with no argument"
    line = marker_broadcast(g, 0)
    assert not line.passed and line.points == 0
    assert line.value == pytest.approx(math.dist((0.0, 0.0, 0.0), MARKERS[0]))


def test_a_stored_frame_sent_on_without_detections_is_judged_where_it_shows() -> None:
    """The faulty broadcast_without_detection: after the marker left the view, the stored
    pose is broadcast again on every frame, relative to wherever the camera is now ("in RViz
    marker_frame follows the robot around"): those broadcasts count for the marker's frame."""
    g = Grader(world())
    drive(g, "explorer", [TARGETS[0]], 4 * S)
    camera(g, 5 * S)
    detect(g, [0], 5 * S)
    send(g, contract.MARKER_FRAME, MARKERS[0], 5 * S)
    assert marker_broadcast(g, 0).passed
    for k in range(1, 6):  # driving on, nothing in view, the camera 0.5 m further each time
        t = 5 * S + k * S
        camera(g, t, x=0.5 * k)
        empty(g, t)
        send(g, contract.MARKER_FRAME, MARKERS[0], t)
    line = marker_broadcast(g, 0)
    assert not line.passed and line.points == 0, line.measured
    assert not only_on_detection(g).passed


def test_broadcasts_while_the_explorer_turns_fast_do_not_decide() -> None:
    """move_base turning the explorer at 2 rad/s at the target: a frame stamped "now" then is
    off by the turn; the scan's slow turn decides."""
    g = Grader(world())

    def at(yaw: float, t: int) -> None:
        q = msgs.Quaternion(z=math.sin(yaw / 2), w=math.cos(yaw / 2))
        pose_ = msgs.PoseStamped(
            pose=msgs.Pose(position=msgs.Point(x=TARGETS[0][0], y=TARGETS[0][1]), orientation=q)
        )
        g.feed(contract.truth_pose("explorer"), pose_, t)

    at(0.0, 4 * S)
    for k, t in enumerate((5 * S, 6 * S)):  # the scan: 0.1 rad/s
        at(0.1 * (k + 1), t)
        camera(g, t)
        detect(g, [0], t)
        send(g, contract.MARKER_FRAME, MARKERS[0], t)
    for k in range(3):  # then move_base turns it at 2 rad/s; broadcasts 0.5 m off
        t = 6 * S + (k + 1) * 100 * MS
        at(0.2 + 0.2 * (k + 1), t)
        camera(g, t)
        detect(g, [0], t)
        send(g, contract.MARKER_FRAME, (MARKERS[0][0] + 0.5, MARKERS[0][1], MARKERS[0][2]), t)
    line = marker_broadcast(g, 0)
    assert line.passed and line.measured.startswith("marker_frame: median of 2 broadcasts at"), (
        line.measured
    )


def test_a_dummy_frame_sent_all_along_is_no_frame_of_the_marker() -> None:
    """rpatil10's package: the course template's dummy ``my_frame`` (a fixed place, every
    loop, detection or not) beside the right ``marker_frame``: the marker is broadcast right
    (a TA looks at marker_frame); only_on_detection fails for the dummy."""
    g = Grader(world())
    drive(g, "explorer", [TARGETS[0]], 4 * S)
    for k in range(60):  # 6 s of the dummy at 10 Hz, far from every marker
        t = 1 * S + k * 100 * MS
        camera(g, t)
        send(g, "my_frame", (5.0, -3.0, 0.0), t, parent=contract.MAP)
        if 40 <= k < 45:  # the marker in view for half a second
            detect(g, [0], t)
            send(g, contract.MARKER_FRAME, MARKERS[0], t)
    line = marker_broadcast(g, 0)
    assert line.passed, line.measured
    assert line.measured.startswith("marker_frame: median of 5 broadcasts")
    assert not only_on_detection(g).passed
