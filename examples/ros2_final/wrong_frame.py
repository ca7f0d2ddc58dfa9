"""Faulty ROS 2 final project: the destination read in ``map`` instead of
``final_destination.frame_id`` (``origin1`` .. ``origin4``).

The marker is read and the right ``aruco_<ID>`` values are taken, but ``final_destination`` is
broadcast as a child of ``map``, so the robot drives to the values themselves: it loses
``final_destination.broadcast``, ``destination.reached`` and ``time_limit``.
"""

from usar_replay.api import contract
from usar_replay.missions.ros2_final import ArucoNode, OdomUpdater, TargetReacher


class MapFrameTargetReacher(TargetReacher):
    def destination_frame(self) -> str:
        return contract.MAP  # the bug: should be final_destination.frame_id


def main() -> None:
    OdomUpdater()
    ArucoNode()
    MapFrameTargetReacher()
