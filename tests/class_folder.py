"""A class folder of teams shaped as the course's real hand-ins, each a small catkin package of
Python nodes (they build in seconds: catkin only configures), for the start-up tests (issue 42).

The shapes, each one of the real class's:

* ``template``: the course template's dozen launch files, ``doc/instructions.txt`` with the
  handout's two commands among prose (the world's ``multiple_robots.launch``, then ``rosrun``);
* ``readme_service``: no instructions; its README names a launch file of the team's and a third
  command, ``rosservice call /start "data: true"``, which starts the mission in its callback;
* ``one_node``: no instructions, one executable;
* ``two_nodes``: no instructions, two executables (a TA would ask the team: ``no_mission``);
* ``override``: a README naming the wrong node, and the team's own ``usar.toml [ros1]``.
"""

from __future__ import annotations

import textwrap
from pathlib import Path

from catkintools import package_xml

TEMPLATE_LAUNCH = (
    "multiple_robots.launch",
    "single_robot.launch",
    "robot_amcl.launch",
    "robot_move_base.launch",
    "amcl_explorer.launch",
    "amcl_follower.launch",
    "move_base_explorer.launch",
    "move_base_follower.launch",
    "gmapping.launch",
    "rviz.launch",
    "spawn.launch",
    "go.launch",
)
"""The course template's twelve launch files (``multiple_robots.launch``: the world)."""

SPIN = """
import rospy
rospy.init_node("{name}")
rospy.loginfo("{name} up")
rospy.spin()
"""
FAIL = "import sys\nprint('the wrong node')\nsys.exit(3)\n"
SERVICE = """
import rospy
from std_srvs.srv import SetBool, SetBoolResponse

rospy.init_node("starter")


def start(request):
    rospy.loginfo("started by /start: %s", request.data)
    return SetBoolResponse(True, "ok")


rospy.Service("/start", SetBool, start)
rospy.loginfo("starter waits for /start")
rospy.spin()
"""
WORLD = """<launch>
  <!-- the course's world: its detector is one usar stands in for, its parameter loads -->
  <node name="aruco_detect" pkg="aruco_detect" type="aruco_detect"/>
  <param name="/team/world_file" value="final_world.world"/>
</launch>
"""


def package(folder: Path, name: str, scripts: dict[str, str], launch: dict[str, str]) -> Path:
    """A catkin package ``name`` at ``folder``: ``scripts`` (file -> Python body, installed with
    ``catkin_install_python``: what ``rosrun`` finds) and ``launch`` files (name -> XML)."""
    package_xml(folder, name)
    programs = " ".join(f"scripts/{s}" for s in scripts)
    (folder / "CMakeLists.txt").write_text(
        f"cmake_minimum_required(VERSION 3.0.2)\nproject({name})\nfind_package(catkin REQUIRED)\n"
        "catkin_package()\n"
        + (
            f"catkin_install_python(PROGRAMS {programs}\n"
            "  DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})\n"
            if scripts
            else ""
        ),
        encoding="utf-8",
    )
    (folder / "scripts").mkdir()
    for file, body in scripts.items():
        path = folder / "scripts" / file
        path.write_text("#!/usr/bin/python3\n" + textwrap.dedent(body), encoding="utf-8")
        path.chmod(0o755)
    (folder / "launch").mkdir()
    for file, xml in launch.items():
        (folder / "launch" / file).write_text(xml, encoding="utf-8")
    return folder


def _node_launch(name: str, script: str) -> str:
    node = f'<node pkg="{name}" type="{script}" name="{script[:-3]}" output="screen"/>'
    return f"<launch>{node}</launch>\n"


def make_class(root: Path) -> Path:
    """The five teams above under ``root`` (returned)."""
    launches = {f: "<launch/>\n" for f in TEMPLATE_LAUNCH}
    launches["multiple_robots.launch"] = WORLD
    pkg = package(root / "template", "final_project", {"explorer.py": SPIN.format(name="ex")},
                  launches)
    (pkg / "doc").mkdir()
    (pkg / "doc" / "instructions.txt").write_text(
        "Group 3. Build: catkin_make, then source devel/setup.bash.\n"
        "Terminal 1:\n"
        "  $ roslaunch final_project multiple_robots.launch\n"
        "Terminal 2:\n"
        "  $ rosrun final_project explorer.py\n"
        "To look at the frames: rosrun rviz rviz\n",
        encoding="utf-8",
    )
    team = root / "readme_service"
    package(
        team / "catkin_ws" / "src" / "rescue",
        "rescue",
        {"starter.py": SERVICE, "other.py": SPIN.format(name="other")},
        {"go.launch": _node_launch("rescue", "starter.py"), "other.launch": "<launch/>\n"},
    )
    (team / "README.md").write_text(
        "# Rescue\n\n```\nroslaunch rescue go.launch\nrosservice call /start \"data: true\"\n```\n",
        encoding="utf-8",
    )
    package(root / "one_node", "solo", {"solo.py": SPIN.format(name="solo")},
            {"a.launch": "<launch/>\n", "b.launch": "<launch/>\n"})
    package(root / "two_nodes", "duo",
            {"explorer_node.py": SPIN.format(name="e"), "follower_node.py": SPIN.format(name="f")},
            {})
    team = package(root / "override", "chosen",
                   {"wrong.py": FAIL, "right.py": SPIN.format(name="right")}, {})
    (team / "README.md").write_text("rosrun chosen wrong.py\n", encoding="utf-8")
    (team / "usar.toml").write_text('[ros1]\nnode = "right.py"\n', encoding="utf-8")
    return root


ENDS = """
import rospy
rospy.init_node("{name}")
rospy.sleep({after})
rospy.loginfo("{name} is home")
"""


def make_pair(root: Path) -> Path:
    """A two-node team whose launch ends when its required node is done (the follower home):
    roslaunch then stops the other node with SIGINT, as the course's packages end."""
    launch = (
        '<launch>\n  <node pkg="pair" type="explorer.py" name="explorer" output="screen"/>\n'
        '  <node pkg="pair" type="follower.py" name="follower" output="screen" required="true"/>'
        "\n</launch>\n"
    )
    team = package(
        root / "pair",
        "pair",
        {"explorer.py": SPIN.format(name="explorer"),
         "follower.py": ENDS.format(name="follower", after=1.5)},
        {"pair.launch": launch},
    )
    (team / "README.md").write_text("roslaunch pair pair.launch\n", encoding="utf-8")
    return root
