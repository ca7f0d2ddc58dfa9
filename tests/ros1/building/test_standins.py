"""ros1/standins: usar's underlay source (fiducial_msgs and the stand-in packages), written
and run as it is built (the underlay's build itself:
tests/ros1/building/test_workspace.py and the course
template's recording, tests/e2e/test_ros1_course.py)."""

from __future__ import annotations

import os
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

from usar_replay.ros1.building import ros_debian, standins


def test_every_stand_in_is_a_catkin_package_and_the_tree_is_deterministic(
    tmp_path: Path,
) -> None:
    files = standins.files()
    assert "fiducial_msgs/msg/FiducialTransformArray.msg" in files
    for name in standins.PACKAGES:
        xml = ET.fromstring(files[f"{name}/package.xml"][0])
        assert xml.findtext("name") == name
        assert f"project({name})" in files[f"{name}/CMakeLists.txt"][0].decode()
    assert standins.sha256() == standins.sha256()
    standins.write(tmp_path / "u")
    for rel, (data, mode) in files.items():
        path = tmp_path / "u" / rel
        assert path.read_bytes() == data
        assert path.stat().st_mode & 0o777 == mode


def test_the_replaced_nodes_packages_are_stand_ins_or_debians() -> None:
    """usar drops the nodes of these packages; each is a stand-in of the underlay or a real
    Debian package (robot_state_publisher, rviz), never a name nothing provides."""
    for pkg in standins.REPLACED:
        assert (
            pkg in standins.PACKAGES
            or ros_debian.debian_package(pkg)
            or pkg in ("joint_state_publisher",)
        ), pkg


def test_empty_world_declares_gazebo_ros_arguments() -> None:
    """An ``<include>`` passes any of the real file's arguments; an undeclared one would stop
    roslaunch ("unused args")."""
    root = ET.fromstring(standins.files()["gazebo_ros/launch/empty_world.launch"][0])
    args = {a.get("name") for a in root.iter("arg")}
    assert {"world_name", "paused", "use_sim_time", "gui", "headless", "debug", "verbose"} <= args
    nodes = {(n.get("pkg"), n.get("type")) for n in root.iter("node")}
    assert ("gazebo_ros", "gzserver") in nodes


def test_the_xacro_stand_in_prints_the_robot_description(tmp_path: Path) -> None:
    standins.write(tmp_path / "u")
    xacro = tmp_path / "u" / "xacro" / "xacro"
    urdf = tmp_path / "u" / "turtlebot3_description" / "urdf" / "turtlebot3_waffle.urdf.xacro"
    assert os.access(xacro, os.X_OK)
    done = subprocess.run(
        [str(xacro), "--inorder", str(urdf), "laser_visual:=false"],
        capture_output=True,
        check=True,
    )
    assert done.stdout == urdf.read_bytes()
    assert b'<robot name="turtlebot3_waffle">' in done.stdout
