/**
 * @file main.cpp
 * @brief The team's node: the explorer finds the markers, then the follower visits them
 * (the logic of examples/ros1/usar_course, in a copy of the course's final_project template).
 */
#include <tf2_ros/transform_listener.h>

#include "final_project/robots.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "final_project");
  ros::NodeHandle nh;
  tf2_ros::Buffer buffer(ros::Duration(60.0));
  tf2_ros::TransformListener listener(buffer);
  final_project::Explorer explorer(&nh, &buffer);
  final_project::Follower follower(&nh);
  std::string team;
  nh.param<std::string>("/team/name", team, "(unnamed)");
  double hz = 10.0;
  ros::NodeHandle("~").param("rate", hz, hz);  // param/team.yaml, loaded in team.launch
  ROS_INFO("team %s: %.1f Hz", team.c_str(), hz);
  ros::Rate rate(hz);
  while (ros::ok()) {
    ros::spinOnce();
    if (explorer.step()) {
      if (!follower.started()) {
        follower.start(explorer.markers());
      } else if (follower.step()) {
        break;
      }
    }
    rate.sleep();
  }
  ROS_INFO("mission complete");
  ros::shutdown();
  return 0;
}
