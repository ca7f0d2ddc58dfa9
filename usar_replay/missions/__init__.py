"""missions: the built-in missions, written as nodes on the node API as a student would.

``usar`` (aruco_detect, explorer, follower) and ``ros2_final``. A public import path
(``from usar_replay.missions.usar import ArucoDetect``), like :mod:`usar_replay.api`. They may
import ``core``, ``world``, ``node`` and ``api``, and load no pybullet, mcap or rerun.
"""
