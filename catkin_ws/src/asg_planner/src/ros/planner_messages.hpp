#pragma once
// Conversions between ROS messages and the planner core's types, and the messages the planner
// publishes for rviz and the agent (PlannerState, path, votes, vehicle grid). No decisions: what
// the planner does is in the core; the node (planner_ros.cpp) wires these to its topics.
#include <asg_msgs/PlannerState.h>
#include <geometry_msgs/Pose.h>
#include <nav_msgs/Path.h>
#include <ros/time.h>
#include <sensor_msgs/Image.h>
#include <visualization_msgs/Marker.h>
#include <visualization_msgs/MarkerArray.h>

#include "asg_planner/frame_sync.hpp"
#include "asg_planner/voting_planner.hpp"

namespace asg_planner {

Eigen::Isometry3d toIso(const geometry_msgs::Pose& p);
/// The image's bytes, without a copy: the result holds the message alive.
ImageIn toImage(const sensor_msgs::ImageConstPtr& m);
/// Position, yaw and forward speed of a pose and its twist.
OdomIn toOdom(const geometry_msgs::Pose& pose, double forward_speed);
geometry_msgs::Point point(double x, double y, double z = 0.0);

/// The planner's state after the control tick that gave `c` (path only when it replanned).
asg_msgs::PlannerState stateMessage(const VotingPlanner& planner, const ControlCommand& c, bool replanned);
/// The current plan, drawn on the ground the stack senses (else at map z 0).
nav_msgs::Path pathMessage(const VotingPlanner& planner, const ros::Time& stamp);
/// The vote grid: one cube per voted vertex, coloured by its votes (a DELETE when none).
visualization_msgs::MarkerArray voteMarkers(const VotingPlanner& planner, const ros::Time& stamp);
/// The vehicle grid A* searches (empty above 400 cells a side).
visualization_msgs::Marker vehicleGridMarker(double spacing, double landscape_size);

}  // namespace asg_planner
