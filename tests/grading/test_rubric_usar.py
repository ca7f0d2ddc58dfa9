"""The pure rubric, one line at a time, on hand-made message streams (no log file, no mcap).

Each test builds a tiny world, feeds a :class:`Grader` the messages a run would publish, and
asserts one rubric function's verdict, its numbers and units, and its evidence time; a line
whose event never happened has no evidence time.
"""

from __future__ import annotations

import math
import subprocess
import sys
from typing import Any

import pytest

from usar_replay.core import contract, msgs
from usar_replay.core.settings import Thresholds
from usar_replay.grading.rubric_usar import (
    MAX_FRAMES,
    Disc,
    Grader,
    explorer_home_before_follower,
    explorer_targets,
    follower_home,
    follower_markers,
    in_order,
    judge,
    marker_broadcast,
    marker_detected,
    only_on_detection,
    time_limit,
)
from usar_replay.world.scenario import Marker, RobotStart, Scenario

S = 1_000_000_000
EXPLORER_HOME = (0.0, 0.0)
FOLLOWER_HOME = (0.0, -1.0)
TARGETS = ((2.0, 0.0), (4.0, 0.0))
MARKERS = {0: (2.0, 1.0, 0.2), 1: (4.0, 1.0, 0.2)}


def world(time_limit_s: float = 100.0) -> Scenario:
    return Scenario(
        name="hand-made",
        walls=(),
        markers=tuple(Marker(id=k, x=x, y=y, z=z) for k, (x, y, z) in MARKERS.items()),
        targets=TARGETS,
        explorer=RobotStart(name="explorer", x=EXPLORER_HOME[0], y=EXPLORER_HOME[1]),
        follower=RobotStart(name="follower", x=FOLLOWER_HOME[0], y=FOLLOWER_HOME[1]),
        time_limit_s=time_limit_s,
    )


def pose(x: float, y: float) -> msgs.PoseStamped:
    return msgs.PoseStamped(pose=msgs.Pose(position=msgs.Point(x=x, y=y)))


def drive(g: Grader, robot: str, points: list[tuple[float, float]], t: int) -> int:
    """The robot's true pose at each point, 1 s apart, starting at ``t``; returns the next t."""
    for x, y in points:
        g.feed(contract.truth_pose(robot), pose(x, y), t)
        t += S
    return t


def detect(
    g: Grader, ids: list[int], t: int, *, came: int | None = None
) -> msgs.FiducialTransformArray:
    """The course's detections of the image stamped ``t``, come at log time ``came`` (default
    ``t``: with the image; a tick later where the detector answers a tick later)."""
    arr = msgs.FiducialTransformArray(
        header=msgs.Header(stamp=msgs.Time.from_ns(t), frame_id=contract.OPTICAL_FRAME),
        transforms=tuple(
            # the camera sits at map's origin (see broadcast): a marker's detection is its pose
            msgs.FiducialTransform(
                fiducial_id=k,
                transform=msgs.Transform(
                    translation=msgs.Vector3(x=MARKERS[k][0], y=MARKERS[k][1], z=MARKERS[k][2])
                ),
            )
            for k in ids
        ),
    )
    g.feed(contract.FIDUCIALS, arr, t if came is None else came)
    return arr


def broadcast(
    g: Grader, mid: int, t: int, *, error_m: float = 0.0, parent: str = contract.OPTICAL_FRAME
) -> None:
    """The camera at the origin of ``map`` (identity) and ``marker_frame`` at the true marker
    plus ``error_m`` along x, stamped ``t`` (the image's stamp)."""
    stamp = msgs.Time.from_ns(t)
    x, y, z = MARKERS[mid]
    cam = msgs.TransformStamped(
        header=msgs.Header(stamp=stamp, frame_id=contract.MAP),
        child_frame_id=contract.OPTICAL_FRAME,
        transform=msgs.Transform(rotation=msgs.Quaternion(w=1.0)),
    )
    marker = msgs.TransformStamped(
        header=msgs.Header(stamp=stamp, frame_id=parent),
        child_frame_id=contract.MARKER_FRAME,
        transform=msgs.Transform(
            translation=msgs.Vector3(x=x + error_m, y=y, z=z), rotation=msgs.Quaternion(w=1.0)
        ),
    )
    g.feed(contract.TF, msgs.TFMessage(transforms=(cam,)), t)
    g.feed(contract.TF, msgs.TFMessage(transforms=(marker,)), t)


def good_run(g: Grader) -> None:
    """Every line passes: targets in order, both markers detected and broadcast, home, then the
    follower stops 0.3 m from 0 and from 1 and comes home."""
    t = drive(g, "follower", [FOLLOWER_HOME], S)
    t = drive(g, "explorer", [EXPLORER_HOME, (1.0, 0.0), TARGETS[0]], t)
    detect(g, [0], t)
    broadcast(g, 0, t)
    t = drive(g, "explorer", [(3.0, 0.0), TARGETS[1]], t + S)
    detect(g, [1], t)
    broadcast(g, 1, t)
    t = drive(g, "explorer", [(2.0, 0.0), EXPLORER_HOME], t + S)
    stops = [(2.0, 0.7), (2.0, 0.7), (4.0, 0.7), (4.0, 0.7)]  # stopped 1 s at each marker
    drive(g, "follower", [(1.0, -1.0), *stops, (1.0, -1.0), FOLLOWER_HOME], t)


# --- the one in-order check ----------------------------------------------------------------------


def test_in_order_is_a_greedy_subsequence_of_arrivals() -> None:
    def disc(*entries: int) -> Disc:
        return Disc((0.0, 0.0), 1.0, 1.1, True, entries=list(entries))

    assert in_order([disc(5), disc(9), disc(12)]) == [5, 9, 12]
    # 2 reached only before 1: it fails, and 3 still counts after 1
    assert in_order([disc(5), disc(3), disc(12)]) == [5, None, 12]
    # passing 3 early does not matter when it is reached again in order
    assert in_order([disc(5), disc(9), disc(2, 14)]) == [5, 9, 14]
    # a skipped item does not block the later ones
    assert in_order([disc(), disc(9)]) == [None, 9]


# --- each line -----------------------------------------------------------------------------------


def test_a_clean_stream_passes_every_line() -> None:
    g = Grader(world())
    good_run(g)
    checks = judge(g)
    assert [c.id for c in checks if not c.passed] == []
    assert sum(c.points for c in checks) == pytest.approx(60.0)
    assert len(checks) == 2 + 2 + 2 + 1 + 1 + 2 + 1 + 1 + 2  # + one cmd_vel line per robot


def test_explorer_targets_in_order_with_units_and_evidence() -> None:
    g = Grader(world())
    t = drive(g, "explorer", [EXPLORER_HOME, TARGETS[1], TARGETS[0]], S)
    first, second = explorer_targets(g)
    assert first.passed and first.evidence_ns == 3 * S and first.evidence == "reached"
    assert first.value == pytest.approx(0.0) and first.unit == "m" and first.limit == 0.15
    assert not second.passed and second.points == 0 and second.max_points == 6
    assert "only before target_1" in second.measured and "out of order" in second.measured
    assert second.threshold == "<= 0.15 m, after target_1"
    assert t == 4 * S


def test_a_target_never_reached_says_how_close_and_when() -> None:
    g = Grader(world())
    drive(g, "explorer", [EXPLORER_HOME, (1.0, 0.0), (1.58, 0.0), (1.0, 0.0)], S)
    line = explorer_targets(g)[0]
    assert not line.passed
    assert line.measured == "never reached (closest 0.42 m at 3.0 s)"
    assert line.evidence_ns == 3 * S and line.evidence == "closest approach"
    assert line.value == pytest.approx(0.42)


def test_a_robot_that_never_moved_has_no_evidence_time() -> None:
    """Nothing happened: the closest approach is where it started, not something to look at."""
    g = Grader(world())
    drive(g, "follower", [FOLLOWER_HOME, FOLLOWER_HOME], S)
    for line in follower_markers(g):
        assert not line.passed and line.evidence_ns is None and line.evidence == ""
        assert (
            line.measured.startswith("never stopped (closest")
            and "where it started" in line.measured
        )
        assert "never" in line.measured and "at never" not in line.measured


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


def _empty(g: Grader, t: int) -> None:
    """The detector saw nothing in the image stamped ``t``."""
    g.feed(
        contract.FIDUCIALS,
        msgs.FiducialTransformArray(
            header=msgs.Header(stamp=msgs.Time.from_ns(t), frame_id=contract.OPTICAL_FRAME)
        ),
        t,
    )


def test_a_queued_detection_drained_late_is_a_detection() -> None:
    """A slow loop drains a subscriber queue of 1000: each detection is broadcast once, 0.2 to
    1.1 s after it came, stamped now, while the detector already sees nothing: no violation."""
    g = Grader(world())
    for k in range(3):
        detect(g, [0], 5 * S + k * 100 * MS)
    _empty(g, 5 * S + 300 * MS)
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
    _empty(g, 5 * S + 100 * MS)
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


def judge_failed(g: Grader) -> list[str]:
    return [c.id for c in judge(g) if not c.passed]


def test_explorer_home_before_the_follower_moved() -> None:
    g = Grader(world())
    drive(g, "follower", [FOLLOWER_HOME], S)
    t = drive(g, "explorer", [EXPLORER_HOME, TARGETS[0], TARGETS[1]], S)
    drive(g, "follower", [(0.5, -1.0)], t)  # moves at 4 s, explorer still out
    drive(g, "explorer", [EXPLORER_HOME], t + S)  # home at 5 s
    line = explorer_home_before_follower(g, 3 * S, "target_2")
    assert not line.passed
    assert line.measured == "home at 5.0 s; follower moved at 4.0 s"
    assert line.evidence_ns == 4 * S and line.evidence == "follower moved"
    assert line.value == 5.0 and line.limit == 4.0 and line.unit == "s"


def test_explorer_never_home_has_no_home_time() -> None:
    g = Grader(world())
    drive(g, "explorer", [EXPLORER_HOME, TARGETS[0]], S)
    line = explorer_home_before_follower(g, 2 * S, "target_1")
    assert not line.passed and line.value is None and line.evidence_ns is None
    assert (
        line.measured == "never home after target_1 (ended 2.00 m away); the follower never moved"
    )


def test_follower_markers_in_id_order_then_home() -> None:
    g = Grader(world())
    path = [FOLLOWER_HOME, (4.0, 0.7), (4.0, 0.7), (2.0, 0.7), (2.0, 0.7), FOLLOWER_HOME]
    drive(g, "follower", path, S)
    m0, m1 = follower_markers(g)
    assert m0.passed and m0.evidence_ns == 5 * S and m0.value == pytest.approx(0.3)
    assert not m1.passed and "out of ID order" in m1.measured
    home = follower_home(g)  # on its own: whatever the visits
    assert home.passed and home.evidence_ns == 6 * S and home.value == pytest.approx(0.0)


def test_follower_home_and_time_stand_on_their_own() -> None:
    """A follower that visited no marker (it stopped 1 m short of each) still came home, after
    the explorer: follower.home and time_limit pass; one that never left home fails both."""
    g = Grader(world())
    t = drive(g, "follower", [FOLLOWER_HOME], S)
    t = drive(g, "explorer", [EXPLORER_HOME, (1.0, 0.0), EXPLORER_HOME], t)
    drive(g, "follower", [(1.0, -1.0), (2.0, -0.3), (2.0, -0.3), FOLLOWER_HOME], t)
    assert not any(c.passed for c in follower_markers(g))
    home = follower_home(g)
    assert home.passed and home.evidence_ns == 8 * S, home.measured
    assert "after the explorer (4.0 s)" in home.measured
    assert time_limit(g, home.evidence_ns).passed
    still = Grader(world())
    drive(still, "follower", [FOLLOWER_HOME, FOLLOWER_HOME], S)
    assert follower_home(still).measured == "never left home"
    assert not time_limit(still, follower_home(still).evidence_ns).passed


def test_a_visit_is_a_stop_within_the_stand_off_and_the_goal_tolerance() -> None:
    """The handout's 0.4 m stand-off (in x and in y) plus the template's 0.05 m tolerance plus
    the overshoot: a stop 0.45 m in front of marker 0 and one 0.6 m off on the diagonal of
    marker 1 pass; driving past at 0.1 m without stopping is no visit; a package's own 0.4 m
    tolerance widens the radius."""
    g = Grader(world())
    assert g.visit_radius == pytest.approx(0.4 * 2**0.5 + 0.05 + 0.10)
    front, diagonal = (2.0, 1.0 - 0.45), (4.0 - 0.6 / 2**0.5, 1.0 - 0.6 / 2**0.5)
    path = [FOLLOWER_HOME, front, front, diagonal, diagonal, FOLLOWER_HOME]
    drive(g, "follower", path, S)
    m0, m1 = follower_markers(g)
    assert m0.passed and m0.value == pytest.approx(0.45), m0.measured
    assert m1.passed and m1.value == pytest.approx(0.6), m1.measured
    assert m0.threshold.startswith("<= 0.715685 m")
    past = Grader(world())
    drive(past, "follower", [FOLLOWER_HOME, (2.0, 0.9), (4.0, 0.9), FOLLOWER_HOME], S)
    p0, p1 = follower_markers(past)
    assert not p0.passed and not p1.passed and "never stopped" in p0.measured, p0.measured
    far = (2.0, 1.0 - 0.95)  # 0.95 m out: beyond 0.77 m with the template's tolerance
    short = Grader(world())
    drive(short, "follower", [FOLLOWER_HOME, far, far], S)
    assert not follower_markers(short)[0].passed
    wide = Grader(world(), Thresholds(follower_goal_tolerance_m=0.4))  # the package's own
    drive(wide, "follower", [FOLLOWER_HOME, far, far], S)
    assert follower_markers(wide)[0].passed


def test_time_limit_counts_from_the_log_start() -> None:
    g = Grader(world(time_limit_s=3.0))
    g.feed(contract.ROSOUT, None, S)
    assert time_limit(g, 3 * S).passed
    late = time_limit(g, 5 * S)
    assert not late.passed and late.measured == "4.0 s" and late.threshold == "<= 3 s"
    assert late.value == 4.0 and late.limit == 3.0
    never = time_limit(g, None)
    assert not never.passed and never.value is None and never.evidence_ns is None
    th = Grader(world(), Thresholds(time_limit_s=50.0))
    assert th.resolved_thresholds().time_limit_s == 50.0
    assert Grader(world()).resolved_thresholds().time_limit_s == 100.0


def test_the_rubric_imports_no_mcap_and_no_simulator() -> None:
    code = (
        "import sys, usar_replay.grading.rubric_usar; "
        "bad = [m for m in ('mcap', 'usar_replay.log.bag', 'pybullet', 'rerun')"
        " if m in sys.modules]; "
        "print(bad)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_two_moving_commands_in_one_tick_are_two_publishers() -> None:
    """A spin timer and a navigator both driving the explorer: caught; a stop after a command
    (a goal ending) is not a fight."""
    g = Grader(world())
    good_run(g)
    t = 500_000_000_000
    spin = msgs.Twist(angular=msgs.Vector3(z=0.1))
    drive = msgs.Twist(linear=msgs.Vector3(x=0.2))
    g.feed("/follower/cmd_vel", drive, t)
    g.feed("/follower/cmd_vel", msgs.Twist(), t)  # the navigator stops: fine
    g.feed("/explorer/cmd_vel", drive, t + 1)
    g.feed("/explorer/cmd_vel", spin, t + 1)  # two publishers in one tick
    checks = {c.id: c for c in judge(g)}
    assert checks["follower.cmd_vel_one_publisher"].passed
    bad = checks["explorer.cmd_vel_one_publisher"]
    assert not bad.passed and bad.value == 1.0 and bad.evidence_ns == t + 1
    assert bad.max_points == 0.0  # it flags the run without moving the course's 60 points


# --- broadcasts as a TA sees them in RViz (rubric version 2, issue #32) ---------------------------

MS = 1_000_000


def send(
    g: Grader,
    child: str,
    xyz: tuple[float, float, float],
    t: int,
    *,
    stamp: int | None = None,
    parent: str = contract.OPTICAL_FRAME,
) -> None:
    """One transform on /tf, published at log time ``t``, stamped ``stamp`` (default ``t``)."""
    tf = msgs.TransformStamped(
        header=msgs.Header(stamp=msgs.Time.from_ns(t if stamp is None else stamp), frame_id=parent),
        child_frame_id=child,
        transform=msgs.Transform(
            translation=msgs.Vector3(x=xyz[0], y=xyz[1], z=xyz[2]), rotation=msgs.Quaternion(w=1.0)
        ),
    )
    g.feed(contract.TF, msgs.TFMessage(transforms=(tf,)), t)


def camera(g: Grader, t: int, x: float = 0.0) -> None:
    """The simulator's camera frame at (x, 0, 0) in map at ``t``."""
    send(g, contract.OPTICAL_FRAME, (x, 0.0, 0.0), t, parent=contract.MAP)


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
    one frame on the marker and a stand-off goal frame in front of it (the follower's goal)
    pass; a stand-off frame alone earns half, and says so; 0.4 m behind the marker's face is
    no stand-off (it fails)."""
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
        camera(h, 5 * S)
        drive(h, "explorer", [(3.0, 1.0)], 5 * S)  # in front of the marker's face (+x)
        detect(h, [0], 5 * S)
        for name, where in frames:
            send(h, name, where, 5 * S)
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
        _empty(g, t)
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
