"""Faulty ROS 2 final project: a wrong marker-ID-to-destination mapping.

The destinations are read into a list in the order the parameter names sort *backwards*
(``aruco_3`` first), then indexed by the marker's ID, so marker 1 picks ``aruco_2``. The frame
is right, the value is not: it loses ``destination.chosen``, ``final_destination.broadcast``,
``destination.reached`` and ``time_limit``.
"""

from usar_replay.missions.ros2_final import ArucoNode, OdomUpdater, TargetReacher


class ReversedTargetReacher(TargetReacher):
    def destination_for(self, marker_id: int) -> tuple[float, float]:
        names = sorted(
            {k.rsplit(".", 1)[0] for k in self.get_parameters_by_prefix("final_destination")}
            - {"frame_id"},
            reverse=True,  # the bug: aruco_3, aruco_2, aruco_1, aruco_0
        )
        name = names[marker_id]
        return (
            float(self.get_parameter(f"final_destination.{name}.x").value),
            float(self.get_parameter(f"final_destination.{name}.y").value),
        )


def main() -> None:
    OdomUpdater()
    ArucoNode()
    ReversedTargetReacher()
