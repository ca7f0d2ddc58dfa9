"""A small C++ catkin package whose node busy-waits on its action client as students write it
(issue 43, item 5), for the spinner tests and the bench.

The node sends the explorer two move_base goals (0.5 m ahead of its home, then home) with
actionlib's ``SimpleActionClient(name, true)``, whose own thread takes in the server's status
and result, and waits for each in one of three shapes (its private parameter ``~shape``):

* ``silent``: ``while (!goals.empty()) { if (client.getState() == SUCCEEDED) { ... } }``: no
  spinOnce, no sleep, no log line while it waits: a thread with no pausing point at all;
* ``late``: ``silent`` after a second of sim time asleep: its thread is the graph's at real-time
  priority by then (the recorder gives it before each tick) when it starts to spin;
* ``ok``: ``while (ros::ok()) { if (client.getState() == SUCCEEDED) { ...; sleep } }``: it
  sleeps only once a goal has ended, and between the goals it spins on ``ros::ok()`` alone;
* ``rate``: the same logic in a ``ros::Rate(20)`` loop (the pace the busy shapes are held to).

After each goal it logs ``goal N reached at T`` (``T`` the sim time); after the last,
``all goals reached`` and ``ros::shutdown()``. Written to a test's folder (it builds in some
20 s; the build cache keeps it).
"""

from __future__ import annotations

from pathlib import Path

NAME = "busy_client"
SHAPES = ("silent", "late", "ok", "rate")

MAIN_CPP = r"""
// A node that busy-waits on its action client (usar-replay's test package, issue 43).
#include <actionlib/client/simple_action_client.h>
#include <move_base_msgs/MoveBaseAction.h>
#include <ros/ros.h>
#include <xmlrpcpp/XmlRpcValue.h>

#include <string>
#include <vector>

namespace {

using Client = actionlib::SimpleActionClient<move_base_msgs::MoveBaseAction>;

std::pair<double, double> home(const ros::NodeHandle& nh) {
  XmlRpc::XmlRpcValue value;
  if (!nh.getParam("/explorer/home", value) || value.getType() != XmlRpc::XmlRpcValue::TypeArray ||
      value.size() < 2) {
    return {-1.2, 0.6};
  }
  return {static_cast<double>(value[0]), static_cast<double>(value[1])};
}

move_base_msgs::MoveBaseGoal goal_at(double x, double y) {
  move_base_msgs::MoveBaseGoal goal;
  goal.target_pose.header.frame_id = "map";
  goal.target_pose.header.stamp = ros::Time::now();
  goal.target_pose.pose.position.x = x;
  goal.target_pose.pose.position.y = y;
  goal.target_pose.pose.orientation.w = 1.0;
  return goal;
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "busy_client");
  ros::NodeHandle nh;
  ros::NodeHandle own("~");
  std::string shape = "silent";
  own.getParam("shape", shape);
  Client client("/explorer/move_base", true);  // its own thread spins the client's callbacks
  client.waitForServer();
  const auto start = home(nh);
  // the last goal first: goals.back() is the next one
  std::vector<std::pair<double, double>> goals = {start, {start.first + 0.5, start.second}};
  int reached = 0;
  if (shape == "late") ros::Duration(1.0).sleep();
  client.sendGoal(goal_at(goals.back().first, goals.back().second));
  if (shape == "silent" || shape == "late") {
    while (!goals.empty()) {
      if (client.getState() == actionlib::SimpleClientGoalState::SUCCEEDED) {
        goals.pop_back();
        ROS_INFO("goal %d reached at %.2f", ++reached, ros::Time::now().toSec());
        if (!goals.empty()) client.sendGoal(goal_at(goals.back().first, goals.back().second));
      }
    }
  } else {
    ros::Rate rate(20.0);
    while (ros::ok() && !goals.empty()) {
      if (client.getState() == actionlib::SimpleClientGoalState::SUCCEEDED) {
        goals.pop_back();
        ROS_INFO("goal %d reached at %.2f", ++reached, ros::Time::now().toSec());
        if (!goals.empty()) client.sendGoal(goal_at(goals.back().first, goals.back().second));
        ros::Duration(0.5).sleep();
      }
      if (shape == "rate") rate.sleep();
    }
  }
  ROS_INFO("all goals reached");
  ros::shutdown();
  return 0;
}
"""

CMAKE = f"""cmake_minimum_required(VERSION 3.0.2)
project({NAME})
add_compile_options(-std=c++17 -O2)
find_package(catkin REQUIRED COMPONENTS roscpp actionlib move_base_msgs)
catkin_package()
include_directories(${{catkin_INCLUDE_DIRS}})
add_executable({NAME}_node src/main.cpp)
add_dependencies({NAME}_node ${{catkin_EXPORTED_TARGETS}})
target_link_libraries({NAME}_node ${{catkin_LIBRARIES}})
"""

PACKAGE_XML = f"""<?xml version="1.0"?>
<package format="2">
  <name>{NAME}</name>
  <version>1.0.0</version>
  <description>usar-replay's test package: a node busy-waiting on its action client.</description>
  <maintainer email="usar@example.invalid">usar-replay</maintainer>
  <license>MIT</license>
  <buildtool_depend>catkin</buildtool_depend>
  <depend>roscpp</depend>
  <depend>actionlib</depend>
  <depend>move_base_msgs</depend>
</package>
"""


def launch_file(shape: str) -> str:
    """The launch file name of ``shape``."""
    return f"{shape}.launch"


def write(folder: Path) -> Path:
    """The package in ``folder`` (made), one launch file per shape; returns ``folder``."""
    (folder / "src").mkdir(parents=True)
    (folder / "launch").mkdir()
    (folder / "package.xml").write_text(PACKAGE_XML, encoding="utf-8")
    (folder / "CMakeLists.txt").write_text(CMAKE, encoding="utf-8")
    (folder / "src" / "main.cpp").write_text(MAIN_CPP, encoding="utf-8")
    for shape in SHAPES:
        (folder / "launch" / launch_file(shape)).write_text(
            f'<launch>\n  <node pkg="{NAME}" type="{NAME}_node" name="{NAME}" output="screen"'
            f' required="true">\n    <param name="shape" value="{shape}"/>\n  </node>\n</launch>\n',
            encoding="utf-8",
        )
    return folder
