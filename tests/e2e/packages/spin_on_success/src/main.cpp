/**
 * @file main.cpp
 * @brief One move_base goal half a metre ahead of the explorer's home; when the main loop sees
 * it SUCCEEDED, one twist (angular.z = 0.3) and never another; three seconds later, shutdown.
 *
 * The robot turns only if that twist is its last command: move_base must publish its zero
 * velocity before its result, as the real one does.
 */
#include <actionlib/client/simple_action_client.h>
#include <geometry_msgs/Twist.h>
#include <move_base_msgs/MoveBaseAction.h>
#include <ros/ros.h>
#include <xmlrpcpp/XmlRpcValue.h>

namespace {

using MoveBaseClient = actionlib::SimpleActionClient<move_base_msgs::MoveBaseAction>;

/// The explorer's home (x, y) from the parameter server; the one-room world's if absent.
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
  ros::init(argc, argv, "spin_on_success");
  ros::NodeHandle nh;
  ros::Publisher cmd_vel = nh.advertise<geometry_msgs::Twist>("/explorer/cmd_vel", 10);
  MoveBaseClient client("/explorer/move_base", true);
  client.waitForServer();

  const auto start = home(nh);
  move_base_msgs::MoveBaseGoal goal;
  goal.target_pose.header.frame_id = "map";
  goal.target_pose.header.stamp = ros::Time::now();
  goal.target_pose.pose.position.x = start.first + 0.5;
  goal.target_pose.pose.position.y = start.second;
  goal.target_pose.pose.orientation.w = 1.0;
  client.sendGoal(goal);

  bool spinning = false;
  ros::Time spun_at;
  ros::Rate rate(20.0);
  while (ros::ok()) {
    ros::spinOnce();
    const auto state = client.getState();
    if (!spinning && state == actionlib::SimpleClientGoalState::SUCCEEDED) {
      geometry_msgs::Twist spin;
      spin.angular.z = 0.3;
      cmd_vel.publish(spin);  // once: the robot keeps its last command
      spinning = true;
      spun_at = ros::Time::now();
      ROS_INFO("goal reached: spinning");
    } else if (state == actionlib::SimpleClientGoalState::ABORTED) {
      ROS_ERROR("goal aborted: %s", state.getText().c_str());
      break;
    }
    if (spinning && ros::Time::now() - spun_at >= ros::Duration(3.0)) {
      ROS_INFO("done");
      break;
    }
    rate.sleep();
  }
  ros::shutdown();
  return 0;
}
