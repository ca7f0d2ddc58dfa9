"""ros1/amcl: ``/<robot>/amcl_pose`` as amcl publishes it: once at start, then on motion past
``update_min_d`` or ``update_min_a``, in ``map``, stamped at sim time."""

from __future__ import annotations

import math

from usar_replay.core import contract, msgs
from usar_replay.core.rotations import yaw_from_quat
from usar_replay.ros1.amcl import COVARIANCE, AmclPose


def test_the_first_pose_is_published_then_only_motion_past_a_threshold() -> None:
    amcl = AmclPose("explorer")
    assert amcl.topic == contract.amcl_pose("explorer") == "/explorer/amcl_pose"
    assert amcl.tick(1_000_000_000, None) is None  # no tf yet: nothing
    first = amcl.tick(1_050_000_000, (-4.0, 2.5, 0.0))
    assert isinstance(first, msgs.PoseWithCovarianceStamped)
    assert first.header.frame_id == contract.MAP
    assert first.header.stamp == msgs.Time.from_ns(1_050_000_000)
    assert (first.pose.pose.position.x, first.pose.pose.position.y) == (-4.0, 2.5)
    assert first.pose.covariance == COVARIANCE
    assert amcl.tick(1_100_000_000, (-3.8, 2.5, 0.1)) is None  # 0.2 m, 0.1 rad: no update
    moved = amcl.tick(1_150_000_000, (-3.7, 2.5, 0.1))  # 0.3 m from the last published
    assert moved is not None and moved.pose.pose.position.x == -3.7
    assert amcl.tick(1_200_000_000, (-3.7, 2.5, 0.25)) is None  # 0.15 rad
    turned = amcl.tick(1_250_000_000, (-3.7, 2.5, 0.35))  # 0.25 rad
    assert turned is not None
    assert math.isclose(yaw_from_quat(turned.pose.pose.orientation), 0.35, abs_tol=1e-9)


def test_the_package_thresholds_and_the_wrap_of_the_angle() -> None:
    amcl = AmclPose("follower", update_min_d=0.05, update_min_a=0.5)
    assert amcl.tick(1, (0.0, 0.0, math.pi - 0.1)) is not None
    assert amcl.tick(2, (0.0, 0.0, -math.pi + 0.1)) is None  # 0.2 rad across the wrap
    assert amcl.tick(3, (0.06, 0.0, -math.pi + 0.1)) is not None


def test_the_same_poses_give_the_same_messages() -> None:
    poses = [(0.01 * i, 0.0, 0.03 * i) for i in range(60)]
    a, b = AmclPose("explorer"), AmclPose("explorer")
    got_a = [a.tick(i * 50_000_000, p) for i, p in enumerate(poses)]
    got_b = [b.tick(i * 50_000_000, p) for i, p in enumerate(poses)]
    assert got_a == got_b and sum(m is not None for m in got_a) >= 3
