#include "asg_planner/voting_planner.hpp"

namespace asg_planner {

VotingPlanner::VotingPlanner(const PlannerParams& params)
    : params_(params),
      votes_(params.vote_spacing, params.max_votes),
      ground_(params.projection.ground_cell),
      follower_(params.follower) {}

void VotingPlanner::reset(const Task& task) {
  task_ = task;
  votes_.clear();
  ground_.clear();
  follower_.reset();
  path_ = PlannedPath();
  sensing_ = false;
  sensing_start_ = next_plan_ = 0;
  last_plan_ = -1;
  plans_ = frames_ = 0;
}

size_t VotingPlanner::addFrame(double t, const float* depth, const uint8_t* labels, int width,
                               int height, const Intrinsics& K, const Eigen::Isometry3d& T) {
  if (!sensing_) {
    sensing_ = true;
    sensing_start_ = t;
    next_plan_ = t + params_.first_plan_delay;
  }
  ++frames_;
  return castVotes(depth, labels, width, height, K, T, params_.projection, &votes_, &ground_);
}

ControlCommand VotingPlanner::tick(double t, const VehicleState2D& s, bool* replanned) {
  if (replanned) *replanned = false;
  // 1e-9: stamps are exact multiples of the tick, sums of periods may not be.
  if (sensing_ && t + 1e-9 >= next_plan_) {
    PlannedPath p = planPath(votes_, params_.astar, task_.landscape_size, Eigen::Vector2d(s.x, s.y),
                             Eigen::Vector2d(task_.goal_x, task_.goal_y));
    if (p.found) {
      path_ = p;
      follower_.setPath(path_.points);
    }
    last_plan_ = t;
    next_plan_ += params_.replan_period;
    while (next_plan_ <= t + 1e-9) next_plan_ += params_.replan_period;
    ++plans_;
    if (replanned) *replanned = true;
  }
  return follower_.update(t, s, task_.speed);
}

}  // namespace asg_planner
