/**
 * @file explorer.cpp
 * @brief The explorer: move_base to each lookup target, rotate until a marker is detected,
 * broadcast it as marker_frame, look it up in map, store it by ID, return home.
 */
#include <geometry_msgs/TransformStamped.h>
#include <tf2/LinearMath/Matrix3x3.h>
#include <tf2/LinearMath/Quaternion.h>
#include <xmlrpcpp/XmlRpcValue.h>

#include <algorithm>
#include <cmath>

#include "usar_course/robots.h"

namespace usar_course {

namespace {
const char kMap[] = "map";
const char kMarkerFrame[] = "marker_frame";

double range_of(const fiducial_msgs::FiducialTransform& f) {
  const auto& t = f.transform.translation;
  return std::sqrt(t.x * t.x + t.y * t.y + t.z * t.z);
}
}  // namespace

Pose2D read_pose_param(const ros::NodeHandle& nh, const std::string& name,
                       const Pose2D& fallback) {
  XmlRpc::XmlRpcValue value;
  if (!nh.getParam(name, value) || value.getType() != XmlRpc::XmlRpcValue::TypeArray ||
      value.size() < 2) {
    return fallback;
  }
  Pose2D pose = fallback;
  for (int i = 0; i < std::min(value.size(), 3); ++i) {
    pose[i] = static_cast<double>(value[i]);
  }
  return pose;
}

void send_goal(MoveBaseClient* client, double x, double y, double yaw) {
  move_base_msgs::MoveBaseGoal goal;
  goal.target_pose.header.frame_id = kMap;
  goal.target_pose.header.stamp = ros::Time::now();
  goal.target_pose.pose.position.x = x;
  goal.target_pose.pose.position.y = y;
  goal.target_pose.pose.orientation.z = std::sin(yaw / 2.0);
  goal.target_pose.pose.orientation.w = std::cos(yaw / 2.0);
  client->sendGoal(goal);
}

Explorer::Explorer(ros::NodeHandle* nh, tf2_ros::Buffer* buffer)
    : nh_(nh), buffer_(buffer), client_("/explorer/move_base", true) {
  for (int k = 1;; ++k) {
    XmlRpc::XmlRpcValue value;
    if (!nh_->getParam("/aruco_lookup_locations/target_" + std::to_string(k), value)) break;
    targets_.emplace_back(static_cast<double>(value[0]), static_cast<double>(value[1]));
  }
  home_ = read_pose_param(*nh_, "/explorer/home", {-4.0, 2.5, 0.0});
  nh_->param("/mission/spin_speed", spin_speed_, 0.1);
  nh_->param("/mission/max_detection_range", max_range_, 2.5);
  nh_->param("/mission/settle_frames", settle_frames_, 5);
  ros::NodeHandle("~").param<std::string>("bug", bug_, "");
  cmd_vel_ = nh_->advertise<geometry_msgs::Twist>("/explorer/cmd_vel", 10);
  fiducials_ = nh_->subscribe("/fiducial_transforms", 10, &Explorer::fiducial_callback, this);
  ROS_INFO("explorer: %zu lookup targets", targets_.size());
  client_.waitForServer();
}

bool Explorer::step() {
  switch (state_) {
    case State::kStart:
      next_target();
      break;
    case State::kToTarget:
      if (bug_ == "two_cmd_vel_publishers") {
        // BUG (team 002): the spin publisher runs while move_base drives the explorer
        geometry_msgs::Twist spin;
        spin.angular.z = spin_speed_;
        cmd_vel_.publish(spin);
      }
      if (client_.getState().isDone()) {
        ROS_INFO("explorer: at target_%zu (%s), searching", target_index_ + 1,
                 client_.getState().toString().c_str());
        state_ = State::kSearch;
        search_start_ = ros::Time::now();
        candidate_ = -1;
        pending_.clear();
        samples_.clear();
      }
      break;
    case State::kSearch:
      search();
      break;
    case State::kToHome:
      if (client_.getState().isDone()) {
        ROS_INFO("explorer: home (%s)", client_.getState().toString().c_str());
        state_ = State::kHome;
      }
      break;
    case State::kHome:
      return true;
  }
  return false;
}

bool Explorer::driving() const {
  return (state_ == State::kToTarget || state_ == State::kToHome) &&
         !client_.getState().isDone();
}

void Explorer::next_target() {
  if (target_index_ >= targets_.size()) {
    state_ = State::kToHome;
    send_goal(&client_, home_[0], home_[1], home_[2]);
    return;
  }
  state_ = State::kToTarget;
  const auto& target = targets_[target_index_];
  send_goal(&client_, target.first, target.second, 0.0);
}

void Explorer::search() {
  geometry_msgs::Twist twist;
  if (candidate_ < 0) {
    twist.angular.z = spin_speed_;  // rotate slowly until a marker is seen
    const double full_turn_s = 2.0 * M_PI / spin_speed_ + 5.0;
    if ((ros::Time::now() - search_start_).toSec() > full_turn_s) {
      ROS_WARN("explorer: no marker at target_%zu after a full turn", target_index_ + 1);
      cmd_vel_.publish(geometry_msgs::Twist());
      ++target_index_;
      next_target();
      return;
    }
  }
  cmd_vel_.publish(twist);
  listen();
}

void Explorer::fiducial_callback(const fiducial_msgs::FiducialTransformArray::ConstPtr& msg) {
  if (state_ != State::kSearch || msg->transforms.empty()) return;
  const fiducial_msgs::FiducialTransform* best = nullptr;
  for (const auto& f : msg->transforms) {
    if (markers_.count(f.fiducial_id) != 0) continue;
    if (candidate_ >= 0 && f.fiducial_id != candidate_) continue;
    if (range_of(f) > max_range_) continue;  // a marker of another target, far away
    if (best == nullptr || range_of(f) < range_of(*best)) best = &f;
  }
  if (best == nullptr) return;
  if (candidate_ < 0) {
    ROS_INFO("explorer: marker %d detected (%.2f m)", best->fiducial_id, range_of(*best));
  }
  candidate_ = best->fiducial_id;
  // broadcaster: marker_frame, a child of the camera's optical frame, at the image's stamp
  geometry_msgs::TransformStamped tf;
  tf.header.stamp = msg->header.stamp;
  tf.header.frame_id = msg->header.frame_id;
  tf.child_frame_id = kMarkerFrame;
  tf.transform = best->transform;
  if (bug_ == "identity_broadcast") {
    // BUG (team 001): a broadcast with nothing filled in: marker_frame is the camera itself
    tf.transform = geometry_msgs::Transform();
    tf.transform.rotation.w = 1.0;
  }
  broadcaster_.sendTransform(tf);
  pending_.push_back(msg->header.stamp);
}

void Explorer::listen() {
  // listener: marker_frame in map at each broadcast's stamp, once tf can answer
  while (!pending_.empty()) {
    const ros::Time stamp = pending_.front();
    if (!buffer_->canTransform(kMap, kMarkerFrame, stamp)) {
      if ((ros::Time::now() - stamp).toSec() > 2.0) pending_.erase(pending_.begin());
      return;
    }
    pending_.erase(pending_.begin());
    try {
      const auto tf = buffer_->lookupTransform(kMap, kMarkerFrame, stamp);
      const auto& r = tf.transform.rotation;
      tf2::Matrix3x3 m(tf2::Quaternion(r.x, r.y, r.z, r.w));
      MarkerPose p;
      p.x = tf.transform.translation.x;
      p.y = tf.transform.translation.y;
      const double nx = m[0][2];  // the marker's face normal (its z axis) on the floor
      const double ny = m[1][2];
      const double n = std::hypot(nx, ny);
      if (n > 1e-6) {
        p.normal_x = nx / n;
        p.normal_y = ny / n;
      }
      samples_.push_back(p);
    } catch (const tf2::TransformException& ex) {
      ROS_WARN("%s", ex.what());
    }
  }
  if (candidate_ >= 0 && static_cast<int>(samples_.size()) >= settle_frames_) store(candidate_);
}

void Explorer::store(int id) {
  MarkerPose mean{0.0, 0.0, 0.0, 0.0};
  for (const auto& s : samples_) {
    mean.x += s.x / samples_.size();
    mean.y += s.y / samples_.size();
    mean.normal_x += s.normal_x / samples_.size();
    mean.normal_y += s.normal_y / samples_.size();
  }
  markers_[id] = mean;
  ROS_INFO("marker %d in /map frame: [%.3f, %.3f]", id, mean.x, mean.y);
  ++target_index_;
  next_target();
}

}  // namespace usar_course
