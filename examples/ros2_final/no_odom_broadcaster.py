"""Faulty ROS 2 final project: no ``robot1/odom -> robot1/base_footprint`` broadcaster.

The tf tree stays broken (the simulator does not publish that link; the students' first task is
the node that does). Navigation finds the robot through tf, so it never localises: the robot
never leaves its start, and every rubric line fails, the tf line first.
"""

from usar_replay.missions.ros2_final import ArucoNode, TargetReacher


def main() -> None:
    # OdomUpdater() forgotten: nothing connects robot1/odom to robot1/base_footprint
    ArucoNode()
    TargetReacher()
