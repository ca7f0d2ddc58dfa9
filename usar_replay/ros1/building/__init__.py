"""ros1.building: a course's catkin package built as on a course machine, or ``build_failed``.

One concern, the build side, in one folder (as ``rosbags`` keeps one per concern):
``debian`` (the Debian packages a course machine has, and the check that names the missing
ones), ``ros_debian`` (a ROS package name -> the Debian package that provides it, for hints),
``standins`` (catkin packages named after what usar replaces: gazebo_ros, amcl, move_base,
aruco_detect, turtlebot3's...), ``workspace`` (usar's underlay, the package in a private
overlay, the build cache), ``jail`` (the build in the run's sandbox and limits), ``message``
(a failed build's errors in the student's folder, with a hint), ``tree`` (a built workspace
checked, frozen, listed and verified) and ``layout`` (where the sandbox shows the workspaces).
The catkin packages usar ships live in ``catkin/``.

The face below is what the rest of usar uses; tests reach the modules themselves.
"""

from usar_replay.ros1.building.debian import check as check_debian
from usar_replay.ros1.building.jail import BuildLimits
from usar_replay.ros1.building.workspace import (
    Built,
    Package,
    cache_root,
    cached_build,
    find_package,
    package_sha256,
    private_build,
    remove_tree,
    underlay,
)

__all__ = [
    "BuildLimits",
    "Built",
    "Package",
    "cache_root",
    "cached_build",
    "check_debian",
    "find_package",
    "package_sha256",
    "private_build",
    "remove_tree",
    "underlay",
]
