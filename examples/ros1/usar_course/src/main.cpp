/**
 * @file main.cpp
 * @brief The node: the explorer finds the markers, then the follower visits them.
 */
#include <tf2_ros/transform_listener.h>

#include "usar_course/robots.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "usar_course");
  ros::NodeHandle nh;
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
    rate.sleep();
  }
  ROS_INFO("mission complete");
  ros::shutdown();
  return 0;
}
