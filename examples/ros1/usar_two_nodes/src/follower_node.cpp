/**
 * @file follower_node.cpp
 * @brief The follower node: waits for the explorer's markers and its call of /follower/go
 *        (std_srvs/Trigger), visits the markers, returns home.
 */
#include <geometry_msgs/PoseArray.h>
#include <std_srvs/Trigger.h>

#include <cmath>
#include <map>

#include "usar_two_nodes/robots.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "follower");
  ros::NodeHandle nh;
  std::map<int, usar_two_nodes::MarkerPose> markers;
  bool got = false;
  boost::function<void(const geometry_msgs::PoseArray::ConstPtr&)> on_markers =
      [&](const geometry_msgs::PoseArray::ConstPtr& msg) {
        markers.clear();
        for (std::size_t i = 0; i < msg->poses.size(); ++i) {
          const geometry_msgs::Pose& p = msg->poses[i];
          const double yaw = 2.0 * std::atan2(p.orientation.z, p.orientation.w);
          markers[static_cast<int>(i)] = {p.position.x, p.position.y, std::cos(yaw), std::sin(yaw)};
        }
        got = true;
      };
  ros::Subscriber sub = nh.subscribe<geometry_msgs::PoseArray>("/explorer/marker_poses", 1, on_markers);
  bool go = false;
  boost::function<bool(std_srvs::Trigger::Request&, std_srvs::Trigger::Response&)> on_go =
      [&](std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
        go = true;
        res.success = true;
        res.message = "going";
        return true;
      };
  ros::ServiceServer server = nh.advertiseService("/follower/go", on_go);
  usar_two_nodes::Follower follower(&nh);
  ros::Rate rate(20.0);
  while (ros::ok()) {
    ros::spinOnce();
    if (!got || !go) {
      ROS_INFO_THROTTLE(1.0, "follower: waiting for the explorer's markers and its call");
    } else if (!follower.started()) {
      follower.start(markers);
    } else if (follower.step()) {
      break;
    }
    rate.sleep();
  }
  ROS_INFO("follower: mission complete");
  ros::shutdown();
  return 0;
}
