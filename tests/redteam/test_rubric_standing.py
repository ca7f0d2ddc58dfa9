"""Red team, issue 50 points 1 and 2: no package setting or frame shape widens what the rubric
accepts beyond what a TA watching the demo would.

Built from synthetic message streams on the course world (the robots' true poses, the camera's
place in ``map``, the course's detections and a package's broadcasts, with the course's camera
geometry), so each attack is judged in milliseconds:

* a package that never moves, whose launch file sets ``xy_goal_tolerance: 10.0`` and whose only
  node subscribes to ``/fiducial_transforms``, scores nothing on the targets, the detections and
  the follower (it scored 36/60 on 827b812);
* ``marker_frame`` put 0.5 m ahead of the camera on every detection (the detected pose never
  used) earns nothing on the broadcast lines or ``only_on_detection`` (4/8 and 4/4 before);
* the honest shapes keep their points: a copy of the detection (all of them), a stand-off on
  the camera's line to the marker and one at a fixed offset along the marker's normal (half);
  the empty transform (team 001's bug) loses only the broadcast lines, as it did.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import pytest
from scipy.spatial.transform import Rotation

from usar_replay.core import contract, msgs
from usar_replay.core.rotations import quat_from_yaw
from usar_replay.core.settings import Thresholds
from usar_replay.grading.usar import Grader, judge
from usar_replay.world.scenario import course_world

S = 1_000_000_000
MS = 1_000_000
WORLD = course_world()
MARKERS = {m.id: m for m in WORLD.markers}
SEEN_FROM = {0: 0, 1: 1, 2: 3, 3: 2}
"""Target index -> the marker seen from it (course-world.md)."""
OPTICAL = Rotation.from_euler("xyz", [-math.pi / 2, 0.0, -math.pi / 2])
CAMERA_OFFSET = (0.069, -0.047, 0.117)
Vec = tuple[float, float, float]
Shape = Callable[[Vec, Rotation], Vec]
"""A package's frame: its origin in the camera frame, from the detection (origin, rotation)."""


def _quat(r: Rotation) -> msgs.Quaternion:
    x, y, z, w = r.as_quat()
    return msgs.Quaternion(x=float(x), y=float(y), z=float(z), w=float(w))


def _truth(g: Grader, robot: str, x: float, y: float, yaw: float, t: int) -> None:
    pose = msgs.Pose(position=msgs.Point(x=x, y=y), orientation=quat_from_yaw(yaw))
    g.feed(contract.truth_pose(robot), msgs.PoseStamped(pose=pose), t)


def _tf(g: Grader, parent: str, child: str, xyz: Vec, rot: Rotation, t: int) -> None:
    tf = msgs.TransformStamped(
        header=msgs.Header(stamp=msgs.Time.from_ns(t), frame_id=parent),
        child_frame_id=child,
        transform=msgs.Transform(
            translation=msgs.Vector3(x=xyz[0], y=xyz[1], z=xyz[2]), rotation=_quat(rot)
        ),
    )
    g.feed(contract.TF, msgs.TFMessage(transforms=(tf,)), t)


def _marker_axes(mid: int) -> Rotation:
    """An ArUco marker's frame in map: z out of its face (the marker's +x), y up."""
    yaw = MARKERS[mid].yaw
    z = (math.cos(yaw), math.sin(yaw), 0.0)
    return Rotation.from_matrix([[-z[1], 0.0, z[0]], [z[0], 0.0, z[1]], [0.0, 1.0, 0.0]])


def _frame(g: Grader, shape: Shape | None, x: float, y: float, yaw: float, t: int) -> None:
    """One camera image at ``t`` with the explorer at (x, y, yaw): the camera's place on /tf,
    the course's detection of the marker in view, and the package's frame from it."""
    base = Rotation.from_euler("z", yaw)
    off = base.apply(CAMERA_OFFSET)
    cam = (x + off[0], y + off[1], off[2])
    cam_rot = base * OPTICAL
    _tf(g, contract.MAP, contract.OPTICAL_FRAME, cam, cam_rot, t)
    mid = min(MARKERS, key=lambda k: math.hypot(MARKERS[k].x - x, MARKERS[k].y - y))
    m = MARKERS[mid]
    d = cam_rot.inv().apply((m.x - cam[0], m.y - cam[1], m.z - cam[2]))
    d_rot = cam_rot.inv() * _marker_axes(mid)
    found = msgs.FiducialTransform(
        fiducial_id=mid,
        transform=msgs.Transform(
            translation=msgs.Vector3(x=float(d[0]), y=float(d[1]), z=float(d[2])),
            rotation=_quat(d_rot),
        ),
    )
    arr = msgs.FiducialTransformArray(
        header=msgs.Header(stamp=msgs.Time.from_ns(t), frame_id=contract.OPTICAL_FRAME),
        transforms=(found,),
    )
    g.feed(contract.FIDUCIALS, arr, t)
    if shape is not None:
        b = shape((float(d[0]), float(d[1]), float(d[2])), d_rot)
        _tf(g, contract.OPTICAL_FRAME, contract.MARKER_FRAME, b, d_rot, t)


def course_run(g: Grader, shape: Shape | None) -> None:
    """The course package's run: the explorer at each target turns slowly through the marker
    (ten images, 0.1 rad/s), then home; the follower stops 0.4 m out from each marker in ID
    order, then home."""
    t = S
    ex, ey = WORLD.explorer.x, WORLD.explorer.y
    fx, fy = WORLD.follower.x, WORLD.follower.y
    _truth(g, "follower", fx, fy, 0.0, t)
    _truth(g, "explorer", ex, ey, 0.0, t)
    for k, (tx, ty) in enumerate(WORLD.targets):
        m = MARKERS[SEEN_FROM[k]]
        face = math.atan2(m.y - ty, m.x - tx)
        t += 20 * S
        for i in range(10):
            yaw = face - 0.05 + 0.01 * i
            _truth(g, "explorer", tx, ty, yaw, t)
            _frame(g, shape, tx, ty, yaw, t)
            t += 100 * MS
    t += 20 * S
    _truth(g, "explorer", ex, ey, 0.0, t)
    _truth(g, "explorer", ex, ey, 0.0, t + S)
    for mid in sorted(MARKERS):
        m = MARKERS[mid]
        t += 20 * S
        for _ in range(3):  # stopped 1 s, 0.4 m out along the marker's normal
            _truth(g, "follower", m.x + 0.4 * math.cos(m.yaw), m.y + 0.4 * math.sin(m.yaw), 0, t)
            t += S // 2
    t += 20 * S
    _truth(g, "follower", fx, fy, 0.0, t)
    _truth(g, "follower", fx, fy, 0.0, t + S)


def _points(g: Grader, prefix: str) -> float:
    return sum(c.points for c in judge(g) if c.id.startswith(prefix))


def copy(d: Vec, _r: Rotation) -> Vec:
    return d


def ray_stand_off(d: Vec, _r: Rotation) -> Vec:
    """0.4 m short of the marker on the camera's line to it."""
    n = math.hypot(*d)
    return (d[0] * (1 - 0.4 / n), d[1] * (1 - 0.4 / n), d[2] * (1 - 0.4 / n))


def normal_stand_off(d: Vec, r: Rotation) -> Vec:
    """0.4 m out along the marker's normal (its z axis), in the camera frame."""
    v = r.apply((0.0, 0.0, 0.4))
    return (d[0] + v[0], d[1] + v[1], d[2] + v[2])


def ahead(_d: Vec, _r: Rotation) -> Vec:
    """0.5 m along the optical axis, whatever was detected (the attack)."""
    return (0.0, 0.0, 0.5)


def empty(_d: Vec, _r: Rotation) -> Vec:
    """The empty transform (team 001's ``broadcast()`` with nothing filled in): the camera."""
    return (0.0, 0.0, 0.0)


@pytest.mark.parametrize(
    ("shape", "broadcast", "only", "detected"),
    [
        (copy, 8.0, True, 12.0),
        (ray_stand_off, 4.0, True, 12.0),
        (normal_stand_off, 4.0, True, 12.0),
        (ahead, 0.0, False, 0.0),
        (empty, 0.0, True, 12.0),
    ],
)
def test_a_frame_earns_only_what_follows_the_detection(
    shape: Shape, broadcast: float, only: bool, detected: float
) -> None:
    """The course package's run with each shape of marker_frame. The attack (0.5 m ahead of the
    camera, the detection never used) earns nothing on the broadcast lines, and a package
    whose only frame ignores its detections read none of them; the honest shapes keep their
    points; the empty transform (a bug, not a disguise) loses only the broadcast lines, as the
    faulty examples do."""
    g = Grader(WORLD)
    g.detections_read = True  # a ROS 1 package's node subscribes
    course_run(g, shape)
    lines = {c.id: c for c in judge(g)}
    assert _points(g, "explorer.target_") == 12
    assert _points(g, "follower.marker_") == 12
    assert sum(lines[f"marker_{k}.broadcast"].points for k in MARKERS) == broadcast, [
        lines[f"marker_{k}.broadcast"].measured for k in MARKERS
    ]
    only_line = lines["marker_frame.only_on_detection"]
    assert only_line.passed == only, only_line.measured
    assert sum(lines[f"marker_{k}.detected"].points for k in MARKERS) == detected
    verdict = g.frame_verdict(contract.MARKER_FRAME)
    assert verdict == {ahead: "ignores", empty: "empty"}.get(shape, "follows")
    if shape is ahead:
        assert "40 ignoring the detection (marker_frame)" in only_line.measured
        assert "it ignores them" in lines["marker_0.broadcast"].measured
        assert "no frame it broadcast follows a detection" in lines["marker_0.detected"].measured


def never_moves(g: Grader) -> None:
    """Both robots at home for the whole demo; the course's detector sees marker 1 from home
    now and then; the package broadcasts nothing."""
    for k in range(600):
        t = (k + 1) * S
        _truth(g, "explorer", WORLD.explorer.x, WORLD.explorer.y, 0.0, t)
        _truth(g, "follower", WORLD.follower.x, WORLD.follower.y, 0.0, t)
        if k % 10 == 0:
            _frame(g, None, WORLD.explorer.x, WORLD.explorer.y, 0.0, t)


@pytest.mark.parametrize("tolerance", [0.05, 0.4, 10.0])
def test_a_wide_goal_tolerance_widens_the_rubric_no_more_than_the_handout(
    tolerance: float,
) -> None:
    """The package's own ``xy_goal_tolerance`` (10 m: every target "reached" from home) widens
    the radii by at most the handout's 0.4 m: a robot that never left home reached nothing,
    detected nothing at a target and visited no marker."""
    th = Thresholds(explorer_goal_tolerance_m=tolerance, follower_goal_tolerance_m=tolerance)
    g = Grader(WORLD, th)
    g.detections_read = True
    never_moves(g)
    assert g.target_radius == pytest.approx(max(0.15, min(tolerance, 0.4) + 0.1))
    assert g.visit_radius == pytest.approx(0.4 * math.sqrt(2) + min(tolerance, 0.4) + 0.1)
    for prefix in ("explorer.target_", "marker_", "follower.marker_", "follower.home"):
        assert _points(g, prefix) == 0, prefix
    assert sum(c.points for c in judge(g)) == 0


def test_a_wide_tolerance_still_counts_a_stop_within_it() -> None:
    """A package with the handout's 0.4 m tolerance whose explorer stops 0.45 m short of each
    target reaches them (0.4 + 0.1 m), with the template's it does not; 0.6 m short is not
    reached, whatever the package's tolerance."""
    for tolerance, short, reached in ((0.4, 0.45, True), (0.05, 0.45, False), (10.0, 0.6, False)):
        g = Grader(WORLD, Thresholds(explorer_goal_tolerance_m=tolerance))
        _truth(g, "explorer", WORLD.explorer.x, WORLD.explorer.y, 0.0, S)
        for k, (tx, ty) in enumerate(WORLD.targets):
            _truth(g, "explorer", tx - short, ty, 0.0, (k + 2) * 10 * S)
        assert (_points(g, "explorer.target_") == 12) == reached, (tolerance, short)
