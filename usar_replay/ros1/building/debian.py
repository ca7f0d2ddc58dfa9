"""The Debian 12 packages that run a course's ROS 1 package, and the check that names them.

Why Debian's: Debian 12 packages ROS 1 (Noetic-era: roscpp, rospy, tf2_ros, actionlib,
move_base_msgs, catkin, the message generators), so a course package builds and runs with
``apt-get install`` and nothing else; Gazebo, move_base, map_server and aruco_detect are what
usar stands in for (:mod:`.standins`). The list is what a course machine has that Debian
packages and a course package asks for (the course template's ``find_package`` and what teams
add to it: tf, tf2_geometry_msgs, std_srvs, image_transport, cv_bridge, ...); each package is
there for a named reason, and apt pulls in the rest (roscpp's headers, the message packages'
dependencies). For anything else a package asks for, the build's hint names the Debian package
(:mod:`.ros_debian`).

Python: Debian's ROS 1 Python packages live in ``/usr/lib/python3/dist-packages`` for Debian's
``/usr/bin/python3``, which is 3.11 like usar's. The bridge process runs usar's own interpreter
and *appends* that folder to its ``sys.path`` (:func:`python_path`): usar's own dependencies
(numpy, OpenCV) keep winning over Debian's, and nothing is written into a virtual environment.
catkin and roslaunch run as Debian's own programs (``/usr/bin/python3``, by their ``#!``).
"""

from __future__ import annotations

from pathlib import Path

from usar_replay.core.errors import MissingRos1

__all__ = [
    "APT_PACKAGES", "CODE_TOOLS", "DIST_PACKAGES", "MissingRos1", "check", "install_line", "missing"
]  # fmt: skip

DIST_PACKAGES = Path("/usr/lib/python3/dist-packages")
"""Where Debian installs rospy, actionlib, tf2_ros and the generated Python messages."""

APT_PACKAGES: dict[str, str] = {
    "g++": "the C++ compiler",
    "cmake": "catkin_make's build system",
    "make": "the build program cmake generates for (cmake only recommends it: a fresh Debian 12 "
    "with --no-install-recommends has none)",
    "catkin": "catkin_make and the catkin CMake macros",
    "ros-message-generation": "message_generation (fiducial_msgs is generated at build time)",
    "ros-std-msgs": "std_msgs .msg definitions (fiducial_msgs' Header)",
    "ros-geometry-msgs": "geometry_msgs .msg definitions (fiducial_msgs' Transform)",
    "libroscpp-dev": "roscpp, the students' C++ client library",
    "libtf2-ros-dev": "tf2_ros: TransformBroadcaster, Buffer, TransformListener",
    "libactionlib-dev": "actionlib: the move_base action clients",
    "libmove-base-msgs-dev": "move_base_msgs for C++",
    "libnav-msgs-dev": "nav_msgs for C++ (odometry, the map)",
    "libsensor-msgs-dev": "sensor_msgs for C++ (camera image and info)",
    "libgeometry-msgs-dev": "geometry_msgs for C++ (the course template's find_package)",
    "libtf-dev": "tf (the course template's find_package; tf::TransformListener)",
    "libtf2-geometry-msgs-dev": "tf2_geometry_msgs (tf2::doTransform, tf2::fromMsg)",
    "libstd-srvs-dev": "std_srvs (Empty, Trigger, SetBool services between a team's nodes)",
    "libimage-transport-dev": "image_transport (listed by teams that read the camera)",
    "libcv-bridge-dev": "cv_bridge (the camera's images as OpenCV matrices)",
    "libvisualization-msgs-dev": "visualization_msgs (markers a team publishes for rviz)",
    "libangles-dev": "angles (angles::normalize_angle, shortest_angular_distance)",
    "python3-rosmaster": "the ROS master (a private one per run)",
    "python3-roslaunch": "roslaunch, to start the package's launch file",
    "rosbash": "rosrun, to start one node of the package (--node)",
    "python3-rospy": "rospy, the bridge's client library",
    "python3-tf2-ros": "tf2_msgs for the bridge's /tf",
    "python3-actionlib": "the bridge's move_base action servers",
    "python3-move-base-msgs": "move_base_msgs for the bridge",
    "python3-nav-msgs": "nav_msgs for the bridge",
    "python3-sensor-msgs": "sensor_msgs for the bridge",
    "python3-rosservice": "rosservice call, a TA's third command (--after-launch)",
    "python3-rostopic": "rostopic pub, a TA's third command (--after-launch)",
    "python3-std-srvs": "std_srvs in Python, for rosservice call /start (SetBool, Trigger)",
    "doxygen": "usar code: documentation coverage from doxygen's XML",
    "cppcheck": "usar code: unused functions, unread variables, lint",
    "clang-format": "usar code: formatting against the course's (Google) style",
    "poppler-utils": "usar code: the report's text and pages (pdftotext)",
    "hunspell": "usar code: the report's spelling",
    "hunspell-en-us": "usar code: the en_US dictionary hunspell checks against",
}
"""What ``apt-get install`` needs, with why (``--no-install-recommends`` is enough)."""

CODE_TOOLS = frozenset(
    {"doxygen", "cppcheck", "clang-format", "poppler-utils", "hunspell", "hunspell-en-us"}
)
"""The packages ``usar code`` needs and ``--ros1`` does not: in the one apt line, but never
a reason for :func:`check` to refuse a run (``usar code`` names a missing one itself)."""

# a file each package installs: the check looks for these, never runs apt or dpkg
_PROBES: dict[str, str] = {
    "g++": "/usr/bin/g++",
    "cmake": "/usr/bin/cmake",
    "make": "/usr/bin/make",
    "catkin": "/usr/bin/catkin_make",
    "ros-message-generation": "/usr/share/message_generation/package.xml",
    "ros-std-msgs": "/usr/share/std_msgs/msg/Header.msg",
    "ros-geometry-msgs": "/usr/share/geometry_msgs/msg/Transform.msg",
    "libroscpp-dev": "/usr/include/ros/ros.h",
    "libtf2-ros-dev": "/usr/include/tf2_ros/transform_broadcaster.h",
    "libactionlib-dev": "/usr/include/actionlib/client/simple_action_client.h",
    "libmove-base-msgs-dev": "/usr/include/move_base_msgs/MoveBaseAction.h",
    "libnav-msgs-dev": "/usr/include/nav_msgs/Odometry.h",
    "libsensor-msgs-dev": "/usr/include/sensor_msgs/Image.h",
    "libgeometry-msgs-dev": "/usr/share/geometry_msgs/cmake/geometry_msgsConfig.cmake",
    "libtf-dev": "/usr/include/tf/transform_listener.h",
    "libtf2-geometry-msgs-dev": "/usr/include/tf2_geometry_msgs/tf2_geometry_msgs.h",
    "libstd-srvs-dev": "/usr/include/std_srvs/Empty.h",
    "libimage-transport-dev": "/usr/include/image_transport/image_transport.h",
    "libcv-bridge-dev": "/usr/include/cv_bridge/cv_bridge.h",
    "libvisualization-msgs-dev": "/usr/include/visualization_msgs/Marker.h",
    "libangles-dev": "/usr/share/angles/cmake/anglesConfig.cmake",
    "python3-rosmaster": "/usr/bin/rosmaster",
    "python3-roslaunch": "/usr/bin/roslaunch",
    "rosbash": "/usr/bin/rosrun",
    "python3-rospy": str(DIST_PACKAGES / "rospy" / "__init__.py"),
    "python3-tf2-ros": str(DIST_PACKAGES / "tf2_msgs" / "msg" / "__init__.py"),
    "python3-actionlib": str(DIST_PACKAGES / "actionlib" / "__init__.py"),
    "python3-move-base-msgs": str(DIST_PACKAGES / "move_base_msgs" / "msg" / "__init__.py"),
    "python3-nav-msgs": str(DIST_PACKAGES / "nav_msgs" / "msg" / "__init__.py"),
    "python3-sensor-msgs": str(DIST_PACKAGES / "sensor_msgs" / "msg" / "__init__.py"),
    "python3-rosservice": "/usr/bin/rosservice",
    "python3-rostopic": "/usr/bin/rostopic",
    "python3-std-srvs": str(DIST_PACKAGES / "std_srvs" / "srv" / "__init__.py"),
    "doxygen": "/usr/bin/doxygen",
    "cppcheck": "/usr/bin/cppcheck",
    "clang-format": "/usr/bin/clang-format",
    "poppler-utils": "/usr/bin/pdftotext",
    "hunspell": "/usr/bin/hunspell",
    "hunspell-en-us": "/usr/share/hunspell/en_US.dic",
}


def install_line(packages: list[str] | None = None) -> str:
    """``apt-get install -y --no-install-recommends ...`` for ``packages`` (default: all)."""
    names = packages if packages is not None else list(APT_PACKAGES)
    return "apt-get install -y --no-install-recommends " + " ".join(names)


def missing(*, code: bool = False) -> list[str]:
    """The Debian packages of :data:`APT_PACKAGES` that a ROS 1 run needs (``code``: those
    ``usar code`` needs) and are not installed here (on another system: all of them)."""
    return [
        name for name, probe in _PROBES.items()
        if (name in CODE_TOOLS) == code and not Path(probe).exists()
    ]  # fmt: skip


def check() -> None:
    """Raise :class:`MissingRos1` naming exactly what to install, or return."""
    gone = missing()
    if gone:
        raise MissingRos1(
            "--ros1 needs Debian 12's ROS 1 packages; missing: "
            + ", ".join(gone)
            + f"; install them (as root) with: apt-get update && {install_line(gone)}"
        )
