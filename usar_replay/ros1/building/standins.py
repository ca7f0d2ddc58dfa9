"""usar's underlay: the catkin packages a course machine has that usar replaces, as names.

Why: a package cloned from the course template asks for what the course machine has:
``find_package(catkin REQUIRED COMPONENTS ... gazebo_ros fiducial_msgs)``, ``<depend>``,
``$(find gazebo_ros)/launch/empty_world.launch``, ``$(find xacro)/xacro ... turtlebot3_waffle``,
nodes of ``amcl``, ``move_base``, ``map_server``, ``aruco_detect``. Debian 12 packages none of
these, and usar does their job itself (its world, its detector, its move_base action servers,
its ``/map`` and ``/tf``). So usar's underlay holds a catkin package of each name: enough for
``find_package``, ``$(find X)`` and ``<include>`` (with the arguments the real launch files
declare) to resolve, nothing that runs. Their launch files name the real nodes (Gazebo's
``gzserver``, ``spawn_model``, ``move_base``...), which usar drops when it starts the launch
file (:data:`REPLACED`, :mod:`.launch_filter`), so ``usar info`` says what was replaced.

Where Debian has the real package (``robot_state_publisher``, ``rviz``: :mod:`.ros_debian`),
usar stands in for the node, not the package. ``fiducial_msgs`` is real: aruco_detect's
messages, field for field, generated at build time.

The files are generated here (one deterministic tree: :func:`files`), so they are part of the
underlay's cache key (:func:`sha256`) as ``fiducial_msgs`` is.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

__all__ = [
    "COURSE_ENV",
    "COURSE_TARGETS",
    "FIDUCIAL_MSGS",
    "PACING",
    "PACKAGES",
    "REPLACED",
    "UNDERLAY",
    "WORLD_NAMESPACES",
    "files",
    "sha256",
    "write",
]

FIDUCIAL_MSGS = Path(__file__).resolve().parent / "catkin" / "fiducial_msgs"
"""aruco_detect's message package, as usar ships it (Debian has no fiducials)."""
PACING = Path(__file__).resolve().parent / "catkin" / "usar_pacing"
"""usar's pacing shim (:mod:`usar_replay.ros1.pacing.shim`), built in the underlay beside them."""

UNDERLAY = "usar_underlay"
"""The folder in the underlay's ``src/`` that holds ``fiducial_msgs`` and the stand-ins."""

PACKAGES: dict[str, str] = {
    "gazebo_ros": "Gazebo: usar's world is the simulator",
    "gazebo_msgs": "Gazebo's messages: usar's world is the simulator",
    "gazebo_plugins": "Gazebo's plugins: usar simulates the camera and the drive",
    "turtlebot3_description": "the robots' model: usar's world has the robots",
    "turtlebot3_gazebo": "the robots in Gazebo: usar's world has the robots",
    "turtlebot3_navigation": "the robots' navigation: usar's move_base action servers",
    "aruco_detect": "marker detection: usar's detector publishes /fiducial_transforms",
    "amcl": "localization: usar publishes map -> odom on /tf",
    "move_base": "navigation: usar's move_base action servers",
    "map_server": "the map: usar publishes the world's map on /map",
    "xacro": "the robot description: a stand-in that prints the file it is given",
}
"""The stand-in packages (Debian 12 has none of them) and what usar does in their place."""

REPLACED: dict[str, str] = {
    "gazebo_ros": "Gazebo (usar's world)",
    "amcl": "localization (usar's /tf and /<robot>/amcl_pose, with the node's update_min_d/a)",
    "move_base": "navigation (usar's move_base, with the node's goal tolerances)",
    "map_server": "the map (usar's /map)",
    "aruco_detect": "marker detection (usar's detector)",
    "robot_state_publisher": "the robots' frames (usar's /tf)",
    "joint_state_publisher": "the robots' joints (usar's /tf)",
    "rviz": "a viewer (usar view)",
}
"""Packages whose nodes usar does not start from a launch file, and what stands in for them."""

WORLD_NAMESPACES = ("/aruco_lookup_locations",)
"""Parameters that are the world's facts: a launch file's values under them are dropped (the
course's ``param/aruco_lookup.yaml`` names the course world's targets), so the world being
graded is the only one the nodes see (usar sets its parameters last, :mod:`.launch_filter`)."""

COURSE_TARGETS = (
    (-1.752882, 3.246192),
    (-2.510293, 1.125585),
    (-0.289296, -1.282680),
    (7.710214, -1.716889),
)
"""The course world's lookup targets as the template's ``param/aruco_lookup.yaml`` has them
(``aruco_lookup_locations/target_1..4``): a launch file's parameter with one of these values
is the course's target, whatever its name (:func:`.launch_filter.replace_targets`)."""

COURSE_ENV = {"TURTLEBOT3_MODEL": "waffle"}
"""The environment a course machine's shell has (its ``.bashrc``): launch files read
``$(env TURTLEBOT3_MODEL)``."""

_GAZEBO_ARGS = {
    "paused": "false",
    "use_sim_time": "true",
    "extra_gazebo_args": "",
    "gui": "true",
    "recording": "false",
    "headless": "false",
    "debug": "false",
    "physics": "ode",
    "verbose": "false",
    "output": "screen",
    "world_name": "worlds/empty.world",
    "respawn_gazebo": "false",
    "use_clock_frequency": "false",
    "pub_clock_frequency": "100",
    "enable_ros_network": "true",
    "server_required": "false",
    "gui_required": "false",
}
"""gazebo_ros's ``empty_world.launch`` arguments and defaults: an ``<include>`` may pass any."""

_NOTE = "<!-- usar's stand-in: declares what the real one does; usar starts none of its nodes -->"


def _args(args: dict[str, str]) -> str:
    return "".join(f'  <arg name="{k}" default="{v}"/>\n' for k, v in args.items())


def _launch(body: str) -> bytes:
    return f'<?xml version="1.0"?>\n<launch>\n  {_NOTE}\n{body}</launch>\n'.encode()


def _package_xml(name: str, why: str) -> bytes:
    return (
        '<?xml version="1.0"?>\n<package format="2">\n'
        f"  <name>{name}</name>\n  <version>0.0.0</version>\n"
        f"  <description>usar's stand-in for {name} ({why}).</description>\n"
        '  <maintainer email="usar@example.org">usar</maintainer>\n'
        "  <license>BSD</license>\n  <buildtool_depend>catkin</buildtool_depend>\n"
        "</package>\n"
    ).encode()


def _cmake(name: str) -> bytes:
    return (
        f"cmake_minimum_required(VERSION 3.0.2)\nproject({name})\n"
        "find_package(catkin REQUIRED)\ncatkin_package()\n"
    ).encode()


_EMPTY_WORLD = _launch(
    _args(_GAZEBO_ARGS)
    + '  <param name="/use_sim_time" value="$(arg use_sim_time)"/>\n'
    + '  <node name="gazebo" pkg="gazebo_ros" type="gzserver" args="$(arg world_name)"/>\n'
    + '  <group if="$(arg gui)">\n'
    + '    <node name="gazebo_gui" pkg="gazebo_ros" type="gzclient"/>\n'
    + "  </group>\n"
)

_ROBOT = (
    '  <param name="robot_description" command="$(find xacro)/xacro '
    '$(find turtlebot3_description)/urdf/turtlebot3_$(arg model).urdf.xacro"/>\n'
    '  <node name="spawn_urdf" pkg="gazebo_ros" type="spawn_model" args="-urdf -model '
    "turtlebot3_$(arg model) -x $(arg x_pos) -y $(arg y_pos) -z $(arg z_pos) "
    '-param robot_description"/>\n'
)

_TB3_WORLD = _launch(
    _args({"model": "$(env TURTLEBOT3_MODEL)", "x_pos": "0.0", "y_pos": "0.0", "z_pos": "0.0"})
    + '  <include file="$(find gazebo_ros)/launch/empty_world.launch"/>\n'
    + _ROBOT
)

_MOVE_BASE = _launch(
    _args(
        {
            "model": "$(env TURTLEBOT3_MODEL)",
            "cmd_vel_topic": "/cmd_vel",
            "odom_topic": "odom",
            "move_forward_only": "false",
        }
    )
    + '  <node pkg="move_base" type="move_base" name="move_base"/>\n'
)

_AMCL = _launch(
    _args(
        {
            "scan_topic": "scan",
            "initial_pose_x": "0.0",
            "initial_pose_y": "0.0",
            "initial_pose_a": "0.0",
        }
    )
    + '  <node pkg="amcl" type="amcl" name="amcl"/>\n'
)

_NAVIGATION = _launch(
    _args(
        {
            "model": "$(env TURTLEBOT3_MODEL)",
            "map_file": "$(find turtlebot3_navigation)/maps/map.yaml",
            "open_rviz": "true",
            "move_forward_only": "false",
        }
    )
    + '  <node pkg="map_server" name="map_server" type="map_server" args="$(arg map_file)"/>\n'
    + '  <include file="$(find turtlebot3_navigation)/launch/amcl.launch"/>\n'
    + '  <include file="$(find turtlebot3_navigation)/launch/move_base.launch">\n'
    + '    <arg name="model" value="$(arg model)"/>\n'
    + '    <arg name="move_forward_only" value="$(arg move_forward_only)"/>\n'
    + "  </include>\n"
    + '  <node if="$(arg open_rviz)" pkg="rviz" type="rviz" name="rviz"/>\n'
)


def _urdf(model: str) -> bytes:
    return (
        '<?xml version="1.0"?>\n'
        f"<!-- usar's stand-in for turtlebot3_{model}: usar's world has the robot -->\n"
        f'<robot name="turtlebot3_{model}">\n'
        '  <link name="base_footprint"/>\n  <link name="base_link"/>\n'
        '  <joint name="base_joint" type="fixed">\n'
        '    <parent link="base_footprint"/>\n    <child link="base_link"/>\n'
        "  </joint>\n</robot>\n"
    ).encode()


_XACRO = b"""#!/bin/sh
# usar's stand-in for xacro (Debian 12 has none): prints the file it is given, macros not
# expanded (usar's world has the robots; nothing usar starts reads robot_description)
for a in "$@"; do
  case "$a" in
    -*|*:=*) ;;
    *) exec cat -- "$a" ;;
  esac
done
echo '<robot name="robot"/>'
"""

_EXTRA: dict[str, tuple[bytes, int]] = {
    "gazebo_ros/launch/empty_world.launch": (_EMPTY_WORLD, 0o644),
    "turtlebot3_gazebo/launch/turtlebot3_empty_world.launch": (_TB3_WORLD, 0o644),
    "turtlebot3_gazebo/launch/turtlebot3_world.launch": (_TB3_WORLD, 0o644),
    "turtlebot3_navigation/launch/move_base.launch": (_MOVE_BASE, 0o644),
    "turtlebot3_navigation/launch/amcl.launch": (_AMCL, 0o644),
    "turtlebot3_navigation/launch/turtlebot3_navigation.launch": (_NAVIGATION, 0o644),
    "xacro/xacro": (_XACRO, 0o755),
    **{
        f"turtlebot3_description/urdf/turtlebot3_{m}.urdf.xacro": (_urdf(m), 0o644)
        for m in ("burger", "waffle", "waffle_pi")
    },
}


def files() -> dict[str, tuple[bytes, int]]:
    """The underlay's source tree: relative path -> (bytes, mode), ``fiducial_msgs`` and every
    stand-in package, in sorted order."""
    out: dict[str, tuple[bytes, int]] = {}
    for shipped in (FIDUCIAL_MSGS, PACING):
        for p in sorted(shipped.rglob("*")):
            if p.is_file() and not p.is_symlink():
                out[f"{shipped.name}/{p.relative_to(shipped).as_posix()}"] = (
                    p.read_bytes(),
                    0o644,
                )
    for name, why in PACKAGES.items():
        out[f"{name}/package.xml"] = (_package_xml(name, why), 0o644)
        out[f"{name}/CMakeLists.txt"] = (_cmake(name), 0o644)
    out.update(_EXTRA)
    return dict(sorted(out.items()))


def sha256() -> str:
    """sha256 over :func:`files` (path, mode and bytes): the underlay's cache key."""
    h = hashlib.sha256()
    for rel, (data, mode) in files().items():
        raw = rel.encode()
        h.update(len(raw).to_bytes(8, "little") + raw + mode.to_bytes(4, "little"))
        h.update(len(data).to_bytes(8, "little") + data)
    return h.hexdigest()


def write(dest: Path) -> None:
    """Write :func:`files` into ``dest`` (a new folder)."""
    dest.mkdir(parents=True)
    for rel, (data, mode) in files().items():
        path = dest / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
        path.chmod(mode)
