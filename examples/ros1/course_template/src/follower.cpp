/**
 * @file follower.cpp
 * @brief The follower: visit each stored marker in ID order, in front of its face, then home.
 */
#include <cmath>

#include "final_project/robots.h"

namespace final_project {

Follower::Follower(ros::NodeHandle* nh) : client_("/follower/move_base", true) {
  home_ = read_pose_param(*nh, "/follower/home", {-4.0, 3.5, 0.0});
  nh->param("/final_project/standoff", standoff_, 0.3);
  client_.waitForServer();
}

void Follower::start(const std::map<int, MarkerPose>& markers) {
  started_ = true;
  queue_.assign(markers.begin(), markers.end());  // std::map: ascending ID
  ROS_INFO("follower: visiting %zu markers in ID order", queue_.size());
  next_goal();
}

void Follower::next_goal() {
  if (queue_.empty()) {
    going_home_ = true;
    send_goal(&client_, home_[0], home_[1], home_[2]);
    return;
  }
  const MarkerPose& m = queue_.front().second;
  // markers are on walls: stop in front of the face, looking at it
  const double x = m.x + standoff_ * m.normal_x;
  const double y = m.y + standoff_ * m.normal_y;
  ROS_INFO("follower: to marker %d", queue_.front().first);
  send_goal(&client_, x, y, std::atan2(-m.normal_y, -m.normal_x));
}

bool Follower::step() {
  if (!client_.getState().isDone()) return false;
  if (going_home_) {
    ROS_INFO("follower: home (%s)", client_.getState().toString().c_str());
    return true;
  }
  queue_.erase(queue_.begin());
  next_goal();
  return false;
}

}  // namespace final_project
