/**
 * @file explorer_node.cpp
 * @brief The explorer node: finds the markers, publishes them (latched) for the follower, then
 *        tells the follower to go through its std_srvs/Trigger service, as many groups wrote it.
 */
#include <geometry_msgs/PoseArray.h>
#include <std_msgs/Int32.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/transform_listener.h>

#include <cmath>
#include <cstdio>

#include "usar_two_nodes/robots.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "explorer");
  ros::NodeHandle nh;
  tf2_ros::Buffer buffer(ros::Duration(60.0));
  tf2_ros::TransformListener listener(buffer);
  ros::Publisher stored = nh.advertise<geometry_msgs::PoseArray>("/explorer/marker_poses", 1, true);
  ros::Publisher count = nh.advertise<std_msgs::Int32>("/explorer/stored_count", 1, true);
  usar_two_nodes::Explorer explorer(&nh, &buffer);
  std::printf("explorer node: started\n");
  std::fflush(stdout);
  std::fprintf(stderr, "explorer node: a line on stderr\n");
  ros::Rate rate(20.0);
  bool published = false;
  while (ros::ok()) {
    ros::spinOnce();
    if (!published && explorer.step()) {
      geometry_msgs::PoseArray msg;
      msg.header.frame_id = "map";
      msg.header.stamp = ros::Time::now();
      for (const auto& entry : explorer.markers()) {  // std::map: ascending ID
        const usar_two_nodes::MarkerPose& m = entry.second;
        geometry_msgs::Pose pose;
        pose.position.x = m.x;
        pose.position.y = m.y;
        const double yaw = std::atan2(m.normal_y, m.normal_x);
        pose.orientation.z = std::sin(yaw / 2.0);
        pose.orientation.w = std::cos(yaw / 2.0);
        msg.poses.push_back(pose);
      }
      stored.publish(msg);
      std_msgs::Int32 n;
      n.data = static_cast<int>(msg.poses.size());
      count.publish(n);
      published = true;
      ROS_INFO("explorer: home, %zu markers on /explorer/marker_poses", msg.poses.size());
      std_srvs::Trigger go;  // blocks until the follower's next spin answers
      if (ros::service::call("/follower/go", go)) {
        ROS_INFO("explorer: the go call answered: %s", go.response.message.c_str());
      } else {
        ROS_WARN("explorer: the go call failed");
      }
    }
    rate.sleep();
  }
  return 0;
}
