/**
 * @file main.cpp
 * @brief The node: the explorer finds the markers, then the follower visits them.
 *
 * ~busy picks how the main loop waits, as students write it (all three run alike under usar,
 * docs/ros1.md "Pacing"):
 *   ""     : ros::Rate at 20 Hz (the course's way);
 *   "scan" : no sleep at all, `while (ros::ok()) { ...; publish; ros::spinOnce(); }`;
 *   "wait" : a busy wait for move_base before the first clock, and a busy wait for each
 *            goal's end, logging without spinning (the action clients spin their own threads).
 */
#include <tf2_ros/transform_listener.h>

#include <memory>
#include <string>

#include "usar_course/robots.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "usar_course");
  ros::NodeHandle nh;
  std::string busy;
  ros::NodeHandle("~").param<std::string>("busy", busy, "");
  std::unique_ptr<usar_course::MoveBaseClient> probe;  // kept for the run, as students keep it
  if (busy == "wait") {
    // `while (!connected) ROS_INFO(...)`: polls the action server without sleeping
    probe = std::make_unique<usar_course::MoveBaseClient>("/explorer/move_base", true);
    while (ros::ok() && !probe->isServerConnected()) ROS_INFO("waiting for move_base");
  }
  tf2_ros::Buffer buffer(ros::Duration(60.0));
  tf2_ros::TransformListener listener(buffer);
  usar_course::Explorer explorer(&nh, &buffer);
  usar_course::Follower follower(&nh);
  ros::Rate rate(20.0);
  while (ros::ok()) {
    ros::spinOnce();
    if (explorer.step()) {
      if (!follower.started()) {
        follower.start(explorer.markers());
      } else if (follower.step()) {
        break;
      }
    }
    if (busy.empty()) {
      rate.sleep();
    } else if (busy == "wait") {
      while (ros::ok() && explorer.driving()) ROS_INFO("explorer: moving");
      while (ros::ok() && follower.driving()) ROS_INFO("follower: moving");
    }
  }
  ROS_INFO("mission complete");
  ros::shutdown();
  return 0;
}
