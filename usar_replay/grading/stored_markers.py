"""The markers a mission stored, wherever it published them: the status line, summary, report.

Why: the built-in mission publishes its stored markers as a ``FiducialTransformArray`` (IDs
included) on ``/explorer/marker_poses``; a student's ROS 1 package puts them where and how it
likes, most often a ``geometry_msgs/PoseArray`` (no IDs) or a ``PoseStamped`` per marker. So a
stored marker is read from:

* ``/explorer/marker_poses`` as a ``FiducialTransformArray`` (by its IDs);
* any ``PoseArray`` the mission publishes (the latest array is the stored set);
* a ``Pose`` or ``PoseStamped`` on a topic whose name has ``marker`` in it (one marker each).

A pose without an ID is given the ID of the true marker nearest to it (this runs on the
recorder's and the grader's side, which know the world; the mission never sees it). When none
is found, :data:`LOOKED` says where the search went.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

from usar_replay.core import contract, msgs

__all__ = ["LOOKED", "StoredMarkers", "is_marker_topic"]

LOOKED = (
    f"{contract.MARKER_POSES} (FiducialTransformArray), any geometry_msgs/PoseArray, and "
    "Pose/PoseStamped topics named *marker*"
)
"""Where stored markers are looked for (said when none were found)."""

_POSE_TYPES = frozenset(
    {msgs.PoseArray.__msgtype__, msgs.PoseStamped.__msgtype__, msgs.Pose.__msgtype__}
)

Point = tuple[float, float, float]


def is_marker_topic(topic: str, msgtype: str) -> bool:
    """Whether a topic of this type may carry stored markers (see the module doc)."""
    if topic == contract.MARKER_POSES and msgtype == msgs.FiducialTransformArray.__msgtype__:
        return True
    if msgtype == msgs.PoseArray.__msgtype__:
        return True
    return msgtype in _POSE_TYPES and "marker" in topic.lower()


class StoredMarkers:
    """The stored markers seen so far, by marker ID, and the topic they came from."""

    def __init__(self, true_markers: Iterable[tuple[int, Point]]) -> None:
        self._true = sorted(true_markers)
        self.by_id: dict[int, Point] = {}
        self.topics: set[str] = set()

    def note(self, topic: str, value: msgs.Message) -> bool:
        """Take one mission message; True when it was a stored marker's."""
        if not is_marker_topic(topic, type(value).__msgtype__):
            return False
        if isinstance(value, msgs.FiducialTransformArray):
            self.by_id = {f.fiducial_id: _xyz(f.transform.translation) for f in value.transforms}
        elif isinstance(value, msgs.PoseArray):
            found = [_xyz(p.position) for p in value.poses]
            self.by_id = {self._nearest(p): p for p in found if self._true}
        elif isinstance(value, msgs.PoseStamped | msgs.Pose):
            pose = value.pose if isinstance(value, msgs.PoseStamped) else value
            if self._true:
                p = _xyz(pose.position)
                self.by_id[self._nearest(p)] = p
        self.by_id = dict(sorted(self.by_id.items()))
        self.topics.add(topic)
        return True

    @property
    def where(self) -> str:
        """The topics the stored markers came from (``LOOKED`` when none)."""
        return ", ".join(sorted(self.topics)) if self.topics else LOOKED

    def _nearest(self, p: Point) -> int:
        return min(self._true, key=lambda m: (math.dist(p[:2], m[1][:2]), m[0]))[0]


def _xyz(v: msgs.Point | msgs.Vector3) -> Point:
    return (v.x, v.y, v.z)
