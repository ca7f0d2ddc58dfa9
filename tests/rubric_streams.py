"""Hand-made message streams for the pure rubric's tests (tests/grading/usar/): a tiny world,
the robots' true poses, the course's detections and the frames a mission broadcasts.

The camera sits at ``map``'s origin (its transform identity) unless a test moves it, so a
marker's detection is its position in ``map``.
"""

from __future__ import annotations

from usar_replay.core import contract, msgs
from usar_replay.grading.usar import Grader, judge
from usar_replay.world.scenario import Marker, RobotStart, Scenario

S = 1_000_000_000
MS = 1_000_000
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
    g: Grader,
    ids: list[int],
    t: int,
    *,
    came: int | None = None,
    at: tuple[float, float, float] = (0.0, 0.0, 0.0),
) -> msgs.FiducialTransformArray:
    """The course's detections of the image stamped ``t``, come at log time ``came`` (default
    ``t``: with the image; a tick later where the detector answers a tick later), the camera
    at ``at`` in map with map's axes (default: its origin)."""
    arr = msgs.FiducialTransformArray(
        header=msgs.Header(stamp=msgs.Time.from_ns(t), frame_id=contract.OPTICAL_FRAME),
        transforms=tuple(
            # the camera sits at map's origin (see broadcast): a marker's detection is its pose
            msgs.FiducialTransform(
                fiducial_id=k,
                transform=msgs.Transform(
                    translation=msgs.Vector3(
                        x=MARKERS[k][0] - at[0], y=MARKERS[k][1] - at[1], z=MARKERS[k][2] - at[2]
                    )
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


def judge_failed(g: Grader) -> list[str]:
    return [c.id for c in judge(g) if not c.passed]


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


def empty(g: Grader, t: int) -> None:
    """The detector saw nothing in the image stamped ``t``."""
    g.feed(
        contract.FIDUCIALS,
        msgs.FiducialTransformArray(
            header=msgs.Header(stamp=msgs.Time.from_ns(t), frame_id=contract.OPTICAL_FRAME)
        ),
        t,
    )
