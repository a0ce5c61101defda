#pragma once
/// @file voting_planner.hpp
/// The autonomy stack's decision core: votes from labelled depth frames, A* replans on a fixed
/// simulated-time schedule, and the path follower at each control tick. No ROS, no wall clock:
/// every decision is a function of the inputs and their stamps.

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "asg_planner/astar.hpp"
#include "asg_planner/path_follower.hpp"
#include "asg_planner/projection.hpp"
#include "asg_planner/vote_grid.hpp"

namespace asg_planner {

struct PlannerParams {
  double vote_spacing = 5.0;       ///< [m] obstacle (vote) grid spacing
  uint32_t max_votes = 50;         ///< [-] cap per vertex
  double first_plan_delay = 1.0;   ///< [s] after the first frame
  double replan_period = 2.0;      ///< [s]
  AStarParams astar;
  ProjectionParams projection;
  FollowerParams follower;
};

struct Task {
  double goal_x = 0, goal_y = 0;  ///< [m]
  double goal_radius = 11.0;      ///< [m]
  double landscape_size = 100.0;  ///< [m]
  double speed = 5.0;             ///< [m/s]
};

class VotingPlanner {
 public:
  explicit VotingPlanner(const PlannerParams& params = PlannerParams());
  /// A new scenario: clears votes, path and controller state.
  void reset(const Task& task);
  /// Adds one frame's votes. t [s] is its stamp; the first frame starts the sensing clock.
  size_t addFrame(double t, const float* depth, const uint8_t* labels, int width, int height,
                  const Intrinsics& K, const Eigen::Isometry3d& T_map_optical);
  /// Control tick at time t [s]: replans if due (replanned is set), then follows the path.
  ControlCommand tick(double t, const VehicleState2D& state, bool* replanned = nullptr);

  const VoteGrid& votes() const { return votes_; }
  const GroundMap& ground() const { return ground_; }
  const PlannedPath& path() const { return path_; }
  const PathFollower& follower() const { return follower_; }
  const Task& task() const { return task_; }
  const PlannerParams& params() const { return params_; }
  double lastPlanTime() const { return last_plan_; }
  uint32_t plans() const { return plans_; }
  uint32_t frames() const { return frames_; }

 private:
  PlannerParams params_;
  Task task_;
  VoteGrid votes_;
  GroundMap ground_;  ///< the stack's ground estimate (projection.height_above_ground only)
  PathFollower follower_;
  PlannedPath path_;
  bool sensing_ = false;
  double sensing_start_ = 0, last_plan_ = -1, next_plan_ = 0;
  uint32_t plans_ = 0, frames_ = 0;
};

}  // namespace asg_planner
