#pragma once
// PlannerROS: thin ROS adapter of asg_planner::VotingPlanner. Pairs depth and label frames by
// stamp with the odometry of the same stamp, votes, and answers each lockstep Tick once every
// frame the worker published up to it has been voted. Topics and parameters: docs/planner.md.

#include <asg_msgs/ScenarioInfo.h>
#include <asg_msgs/StackError.h>
#include <asg_msgs/Tick.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <tf2_msgs/TFMessage.h>

#include <deque>
#include <map>
#include <memory>
#include <string>

#include "asg_planner/frame_sync.hpp"
#include "asg_planner/parameters.hpp"
#include "asg_planner/voting_planner.hpp"
#include "asg_lockstep/ros/stage_times.hpp"
#include "asg_lockstep/stack_protocol.hpp"
#include "asg_lockstep/stage_clock.hpp"

namespace asg_planner {

/// The ROS adapter's own parameters (what the node is called and what it shows), beside the
/// core's table (parameters.hpp). Defaults here; read by PlannerROS::readParameters.
struct AdapterParams {
  std::string ack_name = "planner";  ///< name used in `stack_ack`
  bool publish_markers = true;       ///< publish the rviz topics
};

/// docs/planner.md's parameter table: the core's rows, then the adapter's (`planner --params`).
std::string plannerNodeParameterTable();

class PlannerROS {
 public:
  PlannerROS(ros::NodeHandle nh, ros::NodeHandle pnh);

 private:
  void readParameters();
  void onScenario(const asg_msgs::ScenarioInfoConstPtr& msg);
  /// Whether depth, labels, odometry and ticks each have a connected publisher (see onScenario).
  bool inputsConnected();
  void onDepth(const sensor_msgs::ImageConstPtr& msg);
  void onLabels(const sensor_msgs::ImageConstPtr& msg);
  void onInfo(const sensor_msgs::CameraInfoConstPtr& msg);
  void onOdom(const nav_msgs::OdometryConstPtr& msg);
  void onTf(const tf2_msgs::TFMessageConstPtr& msg);
  void onTick(const asg_msgs::TickConstPtr& msg);
  // Votes every complete frame, then answers pending ticks whose inputs are all in.
  void process();
  void publishViz(const ros::Time& stamp);
  /// Logs (at debug level) a message dropped as not of the current run.
  void stale(const ros::Time& stamp, const char* what);
  /// Tells the worker this run cannot go on (asg_msgs/StackError).
  void reportError(const std::string& reason);

  ros::NodeHandle nh_, pnh_;
  PlannerParams params_;
  std::string ack_name_;  // AdapterParams::ack_name
  bool publish_markers_ = true;
  std::unique_ptr<VotingPlanner> planner_;
  ros::Publisher cmd_pub_, ack_pub_, error_pub_, state_pub_, path_pub_, votes_pub_, lookahead_pub_, grid_pub_;
  ros::Subscriber scenario_sub_, depth_sub_, labels_sub_, info_sub_, odom_sub_, tf_sub_, tick_sub_;

  // Which run is current, which messages make a frame, when a tick may be answered: the
  // frame synchroniser of the planner core (stamps in ns).
  FrameSync sync_{asg_lockstep::Nanos(ros::Duration(asg_msgs::ScenarioInfo::RUN_WINDOW).toNSec())};
  Intrinsics K_;
  ros::Time base_;  // stamp of simulated time 0 in the current run
  asg_msgs::StackError last_error_;
  // Where the planner's time goes (docs/benchmarks.md).
  enum Stage { kReset, kVotes, kPlan, kPublish };
  asg_lockstep::StageClock clock_{{"reset", "votes", "plan", "publish"}};
  std::unique_ptr<asg_lockstep::StageTimesPublisher> stage_pub_;
};

}  // namespace asg_planner
