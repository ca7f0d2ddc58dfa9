"""``/<robot>/amcl_pose``: amcl's pose estimate, as amcl publishes it (bridge process).

Why: usar stands in for amcl (its ``map -> odom`` is on ``/tf``), and some packages read
amcl's estimate itself (one chooses its goal offset from ``/explorer/amcl_pose``). amcl
publishes a ``geometry_msgs/PoseWithCovarianceStamped`` in ``map`` (latched) once it has its
first pose, then only after a filter update, which it runs when the robot moved more than
``update_min_d`` or turned more than ``update_min_a`` since the last one (amcl's defaults
0.25 m and 0.2 rad; the package's amcl launch may set its own: :mod:`.nav_params`). usar's
estimate is the robot's pose in map as the simulator's tf gives it (what amcl converges to on
this driftless world), stamped at the tick's sim time, with a fixed covariance: the same
inputs, the same messages.
"""

from __future__ import annotations

import math

from usar_replay.core import contract, msgs
from usar_replay.core.rotations import quat_from_yaw

__all__ = ["COVARIANCE", "AmclPose"]

COVARIANCE = tuple(
    {0: 0.0025, 7: 0.0025, 35: 0.0007}.get(i, 0.0) for i in range(36)
)
"""x, y (5 cm standard deviation) and yaw (about 1.5 degrees): a converged amcl's order."""

Pose = tuple[float, float, float]


class AmclPose:
    """One robot's ``amcl_pose`` (see the module doc)."""

    def __init__(self, robot: str, update_min_d: float = 0.25, update_min_a: float = 0.2) -> None:
        self.robot = robot
        self.topic = contract.amcl_pose(robot)
        self.update_min_d = update_min_d
        self.update_min_a = update_min_a
        self._last: Pose | None = None

    def tick(self, t_ns: int, pose: Pose | None) -> msgs.PoseWithCovarianceStamped | None:
        """The message to publish at ``t_ns`` for the robot at ``pose`` (None: none this tick):
        the first pose, then each pose past a threshold from the last one published."""
        if pose is None:
            return None
        if self._last is not None:
            lx, ly, lyaw = self._last
            moved = math.hypot(pose[0] - lx, pose[1] - ly)
            turned = abs(math.remainder(pose[2] - lyaw, 2 * math.pi))
            if moved <= self.update_min_d and turned <= self.update_min_a:
                return None
        self._last = pose
        return msgs.PoseWithCovarianceStamped(
            header=msgs.Header(stamp=msgs.Time.from_ns(t_ns), frame_id=contract.MAP),
            pose=msgs.PoseWithCovariance(
                pose=msgs.Pose(
                    position=msgs.Point(x=pose[0], y=pose[1]), orientation=quat_from_yaw(pose[2])
                ),
                covariance=COVARIANCE,
            ),
        )
