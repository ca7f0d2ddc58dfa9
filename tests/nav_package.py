"""A catkin package of Python nodes that configures usar's stand-ins as a course package does
(issue 43): a move_base launch that loads its own ``dwa_local_planner_params.yaml`` (the
follower's ``xy_goal_tolerance: 0.4``), an explorer move_base in a ``<group ns>`` with a
TrajectoryPlannerROS YAML whose ``yaw_goal_tolerance`` is not a number, an amcl with its own
``update_min_d``, and a mission node that loads the course's ``aruco_lookup.yaml`` as its own
private parameters (under a file name of the team's). The node reads its target, counts
``/explorer/amcl_pose``, drives the explorer 1.2 m east, then the follower 2 m east, and ends.
"""

from __future__ import annotations

from pathlib import Path

from class_folder import package

NAME = "nav_team"

MISSION = """
import math
import actionlib
import rospy
from geometry_msgs.msg import PoseWithCovarianceStamped
from move_base_msgs.msg import MoveBaseAction, MoveBaseGoal

rospy.init_node("mission")
target = rospy.get_param("~aruco_lookup_locations/target_1")
other = rospy.get_param("~my_copy/t2", None)
rospy.loginfo("mission: my target_1 is %s, my copy of target 2 is %s", target, other)
poses = []
rospy.Subscriber("/explorer/amcl_pose", PoseWithCovarianceStamped, poses.append)


def go(robot, x, y):
    client = actionlib.SimpleActionClient("/%s/move_base" % robot, MoveBaseAction)
    client.wait_for_server()
    goal = MoveBaseGoal()
    goal.target_pose.header.frame_id = "map"
    goal.target_pose.header.stamp = rospy.Time.now()
    goal.target_pose.pose.position.x = x
    goal.target_pose.pose.position.y = y
    goal.target_pose.pose.orientation.w = 1.0
    client.send_goal(goal)
    client.wait_for_result()
    return client.get_state()


rospy.sleep(0.5)
rospy.loginfo("mission: %d amcl poses at start", len(poses))
state = go("explorer", 0.0, 0.6)
rospy.sleep(0.5)
rospy.loginfo("mission: explorer ended %d, %d amcl poses", state, len(poses))
state = go("follower", 0.8, -0.9)
rospy.loginfo("mission: follower ended %d", state)
rospy.sleep(0.5)
"""

GO = """<launch>
  <include file="$(find nav_team)/launch/navigation.launch"/>
  <node pkg="nav_team" type="mission.py" name="mission" output="screen" required="true">
    <rosparam file="$(find nav_team)/param/our_targets.yaml" command="load"/>
    <rosparam param="my_copy">{t2: [-2.510293, 1.125585]}</rosparam>
  </node>
</launch>
"""

NAVIGATION = """<launch>
  <node pkg="move_base" type="move_base" name="follower_move_base">
    <param name="base_local_planner" value="dwa_local_planner/DWAPlannerROS"/>
    <rosparam file="$(find nav_team)/param/dwa_local_planner_params.yaml" command="load"/>
    <remap from="cmd_vel" to="/follower/cmd_vel"/>
  </node>
  <group ns="explorer">
    <node pkg="move_base" type="move_base" name="move_base">
      <rosparam file="$(find nav_team)/param/base_local_planner_params.yaml" command="load"/>
    </node>
  </group>
  <node pkg="amcl" type="amcl" name="explorer_amcl">
    <param name="update_min_d" value="0.1"/>
    <remap from="amcl_pose" to="/explorer/amcl_pose"/>
  </node>
</launch>
"""

DWA = """DWAPlannerROS:
  max_vel_x: 0.26
# Goal Tolerance Parameters
  xy_goal_tolerance: {xy}
  yaw_goal_tolerance: 0.17
  latch_xy_goal_tolerance: false
"""

TRAJECTORY = """TrajectoryPlannerROS:
  xy_goal_tolerance: 0.10
  yaw_goal_tolerance: wide
"""

COURSE_TARGETS = """aruco_lookup_locations:
  target_1: [-1.752882, 3.246192]
  target_2: [-2.510293, 1.125585]
  target_3: [-0.289296, -1.282680]
  target_4: [7.710214, -1.716889]
"""


def write(folder: Path, xy: float = 0.4) -> Path:
    """The package at ``folder`` (returned), the follower's tolerance ``xy``."""
    pkg = package(
        folder,
        NAME,
        {"mission.py": MISSION},
        {"go.launch": GO, "navigation.launch": NAVIGATION},
    )
    (pkg / "param").mkdir()
    (pkg / "param" / "dwa_local_planner_params.yaml").write_text(DWA.format(xy=xy))
    (pkg / "param" / "base_local_planner_params.yaml").write_text(TRAJECTORY)
    (pkg / "param" / "our_targets.yaml").write_text(COURSE_TARGETS)
    return pkg
