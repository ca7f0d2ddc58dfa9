/**
 * @file robots.h
 * @brief The explorer and the follower of the US&R final project, one class each.
 *
 * The explorer visits /aruco_lookup_locations/target_1..N with move_base, rotates at each until
 * /fiducial_transforms reports a marker it has not stored yet, broadcasts that marker as
 * marker_frame (a child of the camera's optical frame, stamped with the image's stamp), looks
 * marker_frame up in map with a tf2 listener and stores the pose by marker ID, then returns home.
 * The follower then visits the stored markers in ID order, stopping in front of each, and
 * returns home.
 */
#pragma once

#include <actionlib/client/simple_action_client.h>
#include <fiducial_msgs/FiducialTransformArray.h>
#include <geometry_msgs/Twist.h>
#include <move_base_msgs/MoveBaseAction.h>
#include <ros/ros.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>

#include <array>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace usar_course {

using MoveBaseClient = actionlib::SimpleActionClient<move_base_msgs::MoveBaseAction>;

/** @brief A marker's place in map and the direction its face points to (on the floor). */
struct MarkerPose {
  double x{0.0};
  double y{0.0};
  double normal_x{1.0};
  double normal_y{0.0};
};

/** @brief A pose on the floor: x, y (m) and yaw (rad) in map. */
using Pose2D = std::array<double, 3>;

/** @brief Reads a [x, y(, yaw)] parameter; the fallback when it is not set. */
Pose2D read_pose_param(const ros::NodeHandle& nh, const std::string& name, const Pose2D& fallback);

/** @brief Sends a move_base goal in map. */
void send_goal(MoveBaseClient* client, double x, double y, double yaw);

/** @brief The explorer: targets, search, broadcaster and listener, return home. */
class Explorer {
 public:
  Explorer(ros::NodeHandle* nh, tf2_ros::Buffer* buffer);
  /** @brief One step of the explorer's state machine; true once it is back home. */
  bool step();
  /** @brief The stored markers, by ID. */
  const std::map<int, MarkerPose>& markers() const { return markers_; }
  /** @brief A move_base goal of the explorer's is under way. */
  bool driving() const;

 private:
  enum class State { kStart, kToTarget, kSearch, kToHome, kHome };
  void fiducial_callback(const fiducial_msgs::FiducialTransformArray::ConstPtr& msg);
  void next_target();
  void search();
  void listen();
  void store(int id);

  ros::NodeHandle* nh_;
  tf2_ros::Buffer* buffer_;
  tf2_ros::TransformBroadcaster broadcaster_;
  MoveBaseClient client_;
  ros::Publisher cmd_vel_;
  ros::Subscriber fiducials_;
  std::vector<std::pair<double, double>> targets_;
  Pose2D home_;
  double spin_speed_;
  double max_range_;
  int settle_frames_;
  std::string bug_;  ///< ~bug: one of the course's real bugs, for the faulty launch files
  State state_{State::kStart};
  std::size_t target_index_{0};
  ros::Time search_start_;
  int candidate_{-1};
  std::vector<ros::Time> pending_;  ///< stamps of marker_frame broadcasts not looked up yet
  std::vector<MarkerPose> samples_;
  std::map<int, MarkerPose> markers_;
};

/** @brief The follower: visits the markers in ID order, then returns home. */
class Follower {
 public:
  explicit Follower(ros::NodeHandle* nh);
  /** @brief Starts the visits (call once the explorer is home). */
  void start(const std::map<int, MarkerPose>& markers);
  /** @brief One step; true once the follower is back home. */
  bool step();
  bool started() const { return started_; }
  /** @brief A move_base goal of the follower's is under way. */
  bool driving() const { return started_ && !client_.getState().isDone(); }

 private:
  void next_goal();

  MoveBaseClient client_;
  Pose2D home_;
  double standoff_;
  std::vector<std::pair<int, MarkerPose>> queue_;
  bool started_{false};
  bool going_home_{false};
};

}  // namespace usar_course
