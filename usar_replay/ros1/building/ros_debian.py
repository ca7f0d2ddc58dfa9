"""Which Debian 12 package provides a ROS 1 package, by its ROS name: data and one lookup.

Why a table and not a guess: a team's ``find_package(catkin REQUIRED COMPONENTS X)`` that fails
on a machine set up with the README's apt-get line names a ROS package, and the fix is an
``apt-get install`` of a Debian package whose name follows no single rule (``tf`` is
``libtf-dev``, ``rosgraph_msgs`` is ``libros-rosgraph-msgs-dev``, ``dynamic_reconfigure`` is
``libdynamic-reconfigure-config-init-mutex-dev``, ``rospy`` is ``python3-rospy``). Each row
names the Debian 12 (bookworm) package that installs ``<name>Config.cmake`` (what
``find_package`` looks for), checked against the archive: with ``dpkg -S`` where installed,
with the package's file list (``dpkg -c``) or its description (``apt-cache show``) otherwise.

:data:`NOT_IN_DEBIAN` names ROS packages a course package may ask for that Debian 12 lacks and
usar does not stand in for (:mod:`.standins` lists those it does), with what to do instead.
"""

from __future__ import annotations

__all__ = ["DEBIAN", "GAZEBO", "NOT_IN_DEBIAN", "debian_package", "not_in_debian"]

DEBIAN: dict[str, str] = {
    # build tools and client libraries
    "catkin": "catkin",
    "cmake_modules": "ros-cmake-modules",
    "message_generation": "ros-message-generation",
    "message_runtime": "ros-message-runtime",
    "roscpp": "libroscpp-dev",
    "rospy": "python3-rospy",
    "rosconsole": "librosconsole-dev",
    "roslib": "libroslib-dev",
    "rostest": "librostest-dev",
    "rosbag": "librosbag-dev",
    "roslaunch": "python3-roslaunch",
    "xmlrpcpp": "libxmlrpcpp-dev",
    "cpp_common": "libroscpp-core-dev",
    "rostime": "libroscpp-core-dev",
    "roscpp_serialization": "libroscpp-core-dev",
    "roscpp_traits": "libroscpp-core-dev",
    "class_loader": "libclass-loader-dev",
    "pluginlib": "pluginlib-dev",
    "nodelet": "libnodeletlib-dev",
    "dynamic_reconfigure": "libdynamic-reconfigure-config-init-mutex-dev",
    "actionlib": "libactionlib-dev",
    "message_filters": "libmessage-filters-dev",
    "topic_tools": "libtopic-tools-dev",
    "diagnostic_updater": "libdiagnostic-updater-dev",
    # messages and services
    "std_msgs": "libstd-msgs-dev",
    "std_srvs": "libstd-srvs-dev",
    "geometry_msgs": "libgeometry-msgs-dev",
    "nav_msgs": "libnav-msgs-dev",
    "sensor_msgs": "libsensor-msgs-dev",
    "actionlib_msgs": "libactionlib-msgs-dev",
    "move_base_msgs": "libmove-base-msgs-dev",
    "visualization_msgs": "libvisualization-msgs-dev",
    "diagnostic_msgs": "libdiagnostic-msgs-dev",
    "trajectory_msgs": "libtrajectory-msgs-dev",
    "shape_msgs": "libshape-msgs-dev",
    "stereo_msgs": "libstereo-msgs-dev",
    "pcl_msgs": "libpcl-msgs-dev",
    "rosgraph_msgs": "libros-rosgraph-msgs-dev",
    "tf2_msgs": "libtf2-msgs-dev",
    # transforms
    "tf": "libtf-dev",
    "tf_conversions": "libtf-conversions-dev",
    "tf2": "libtf2-dev",
    "tf2_ros": "libtf2-ros-dev",
    "tf2_geometry_msgs": "libtf2-geometry-msgs-dev",
    "tf2_eigen": "libtf2-eigen-dev",
    "tf2_kdl": "libtf2-kdl-dev",
    "tf2_bullet": "libtf2-bullet-dev",
    "tf2_sensor_msgs": "libtf2-sensor-msgs-dev",
    "angles": "libangles-dev",
    # images, lasers, point clouds
    "image_transport": "libimage-transport-dev",
    "cv_bridge": "libcv-bridge-dev",
    "image_geometry": "libimage-geometry-dev",
    "camera_info_manager": "libcamera-info-manager-dev",
    "camera_calibration_parsers": "libcamera-calibration-parsers-dev",
    "laser_geometry": "liblaser-geometry-dev",
    "pcl_ros": "libpcl-ros-dev",
    "pcl_conversions": "libpcl-conversions-dev",
    # robot model and visualization
    "urdf": "liburdf-dev",
    "kdl_parser": "libkdl-parser-dev",
    "robot_state_publisher": "librobot-state-publisher-dev",
    "interactive_markers": "libinteractive-markers-dev",
    "rviz": "librviz-dev",
    "resource_retriever": "libresource-retriever-dev",
}
"""ROS 1 package name -> the Debian 12 package with its CMake config (``find_package``)."""

GAZEBO = "usar has no Gazebo"
"""Why a package that uses Gazebo's API cannot build here (the hint's first words)."""

_NAVIGATION = "ROS navigation, not in Debian 12; usar's move_base serves the action"

NOT_IN_DEBIAN: dict[str, str] = {
    "gazebo": GAZEBO,
    "gazebo_dev": GAZEBO,
    "gazebo_ros_control": GAZEBO,
    "costmap_2d": _NAVIGATION,
    "nav_core": _NAVIGATION,
    "base_local_planner": _NAVIGATION,
    "dwa_local_planner": _NAVIGATION,
    "global_planner": _NAVIGATION,
    "navfn": _NAVIGATION,
    "clear_costmap_recovery": _NAVIGATION,
    "gmapping": "SLAM, not in Debian 12; usar publishes the world's map on /map",
    "turtlebot3_msgs": "turtlebot3's messages, not in Debian 12; usar simulates the robots",
}
"""ROS packages a course package may name that Debian 12 lacks and usar does not stand in
for: what usar does instead."""


def debian_package(ros_name: str) -> str | None:
    """The Debian package that provides ``ros_name`` to ``find_package``; None when Debian 12
    has none (or the name is not a ROS package this table knows)."""
    return DEBIAN.get(ros_name)


def not_in_debian(ros_name: str) -> str:
    """Why Debian 12 has no ``ros_name`` and what usar does instead; '' when not known."""
    return NOT_IN_DEBIAN.get(ros_name, "")
