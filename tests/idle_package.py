"""A small C++ catkin package that never ends by itself: its node finishes a short mission and
then waits (issue 51, points 6 and 7), for the time-limit tests and the idle-tick bench.

Why: a team whose package does not end (its node spins after the follower is home, a launch
file with no ``required`` node) runs to the world's hard time limit; what such a run costs is
the time limit (how long it runs) times what an idle tick costs (the pacing). The node is
shaped as course packages are: a ``tf2_ros::TransformListener`` (its own thread, waiting on its
queue 10 ms at a time) and a subscriber to ``/fiducial_transforms`` (every frame tick brings a
message to react to). It sends the explorer one move_base goal 0.5 m ahead of its home and waits
for it in a ``ros::Rate(20)`` loop, logs ``mission over at T`` (``T`` the sim time), then, by its
private parameter ``~shape``:

* ``done``: ``ros::shutdown()`` (the finishing package, the baseline);
* ``spin``: ``ros::spin()`` with a 10 Hz ``ros::Timer`` that only counts (a node waiting on its
  callback queue);
* ``rate``: ``while (ros::ok()) { ros::spinOnce(); rate.sleep(); }`` at 10 Hz (the template's
  loop, left running);
* ``poll``: ``while (ros::ok()) { ros::spinOnce(); }`` with no sleep (a busy poll);
* ``silent``: ``for (;;) { if (client.getState() == LOST) break; }``: no call that pauses, as a
  package busy-waiting for a SUCCEEDED that never comes (its goal aborted) spins forever.

Written to a test's folder (it builds in some 20 s; the build cache keeps it).
"""

from __future__ import annotations

from pathlib import Path

NAME = "idle_after"
SHAPES = ("done", "spin", "rate", "poll", "silent")
OVER = "mission over at"
"""The start of the line the node logs when its mission is over (then it idles)."""

MAIN_CPP = r"""
// A node that idles after its mission (usar-replay's test package, issue 51).
#include <actionlib/client/simple_action_client.h>
#include <fiducial_msgs/FiducialTransformArray.h>
#include <move_base_msgs/MoveBaseAction.h>
#include <ros/ros.h>
#include <tf2_ros/transform_listener.h>
#include <xmlrpcpp/XmlRpcValue.h>

#include <string>

namespace {

int seen = 0;
int ticks = 0;

void on_fiducials(const fiducial_msgs::FiducialTransformArray::ConstPtr& msg) {
  seen += static_cast<int>(msg->transforms.size());
}

void on_timer(const ros::TimerEvent&) { ++ticks; }

std::pair<double, double> home(const ros::NodeHandle& nh) {
  XmlRpc::XmlRpcValue value;
  if (!nh.getParam("/explorer/home", value) || value.getType() != XmlRpc::XmlRpcValue::TypeArray ||
      value.size() < 2) {
    return {-1.2, 0.6};
  }
  return {static_cast<double>(value[0]), static_cast<double>(value[1])};
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "idle_after");
  ros::NodeHandle nh;
  ros::NodeHandle own("~");
  std::string shape = "spin";
  own.getParam("shape", shape);
  tf2_ros::Buffer buffer;
  tf2_ros::TransformListener listener(buffer);
  ros::Subscriber sub = nh.subscribe("/fiducial_transforms", 10, on_fiducials);
  actionlib::SimpleActionClient<move_base_msgs::MoveBaseAction> client("/explorer/move_base", true);
  client.waitForServer();
  const auto start = home(nh);
  move_base_msgs::MoveBaseGoal goal;
  goal.target_pose.header.frame_id = "map";
  goal.target_pose.header.stamp = ros::Time::now();
  goal.target_pose.pose.position.x = start.first + 0.5;
  goal.target_pose.pose.position.y = start.second;
  goal.target_pose.pose.orientation.w = 1.0;
  client.sendGoal(goal);
  ros::Rate rate(20.0);
  while (ros::ok() && !client.getState().isDone()) {
    ros::spinOnce();
    rate.sleep();
  }
  ROS_INFO("mission over at %.2f (%s)", ros::Time::now().toSec(), shape.c_str());
  if (shape == "done") {
    ros::shutdown();
    return 0;
  }
  if (shape == "spin") {
    ros::Timer timer = nh.createTimer(ros::Duration(0.1), on_timer);
    ros::spin();
  } else if (shape == "rate") {
    ros::Rate slow(10.0);
    while (ros::ok()) {
      ros::spinOnce();
      slow.sleep();
    }
  } else if (shape == "poll") {
    while (ros::ok()) ros::spinOnce();
  } else {
    for (;;) {
      if (client.getState() == actionlib::SimpleClientGoalState::LOST) break;
    }
  }
  return 0;
}
"""

CMAKE = f"""cmake_minimum_required(VERSION 3.0.2)
project({NAME})
add_compile_options(-std=c++17 -O2)
find_package(catkin REQUIRED COMPONENTS roscpp actionlib move_base_msgs fiducial_msgs tf2_ros)
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
  <description>usar-replay's test package: a node that idles after its mission.</description>
  <maintainer email="usar@example.invalid">usar-replay</maintainer>
  <license>MIT</license>
  <buildtool_depend>catkin</buildtool_depend>
  <depend>roscpp</depend>
  <depend>actionlib</depend>
  <depend>move_base_msgs</depend>
  <depend>fiducial_msgs</depend>
  <depend>tf2_ros</depend>
</package>
"""


def launch_file(shape: str) -> str:
    """The launch file name of ``shape``."""
    return f"{shape}.launch"


def write(folder: Path, default: str = "spin") -> Path:
    """The package in ``folder`` (made), one launch file per shape, and instructions that start
    ``default``'s (as a team's would); returns ``folder``."""
    (folder / "src").mkdir(parents=True)
    (folder / "launch").mkdir()
    (folder / "doc").mkdir()
    (folder / "package.xml").write_text(PACKAGE_XML, encoding="utf-8")
    (folder / "CMakeLists.txt").write_text(CMAKE, encoding="utf-8")
    (folder / "src" / "main.cpp").write_text(MAIN_CPP, encoding="utf-8")
    for shape in SHAPES:
        (folder / "launch" / launch_file(shape)).write_text(
            f'<launch>\n  <node pkg="{NAME}" type="{NAME}_node" name="{NAME}" output="screen">\n'
            f'    <param name="shape" value="{shape}"/>\n  </node>\n</launch>\n',
            encoding="utf-8",
        )
    (folder / "doc" / "instructions.txt").write_text(
        f"roslaunch {NAME} {launch_file(default)}\n", encoding="utf-8"
    )
    return folder
