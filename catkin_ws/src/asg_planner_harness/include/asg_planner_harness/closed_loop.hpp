#pragma once
/// @file closed_loop.hpp
/// The ground-truth-label stack (voting planner + path follower) closed around the simulator
/// core in one process, no ROS, through the simulator's run loop (asg_sim/run_loop.hpp), the
/// scene worker's own: a run follows the same decisions the ROS stack makes. For tools and tests; the planner core itself does not
/// depend on the simulator.

#include <string>
#include <vector>

#include "asg_planner/voting_planner.hpp"
#include "asg_sim/run_loop.hpp"
#include "asg_sim/scenario_runner.hpp"

namespace asg_planner_harness {

using asg_planner::PlannerParams;
using asg_planner::ControlCommand;
using asg_planner::Intrinsics;
using asg_planner::VehicleState2D;
using asg_planner::VotingPlanner;

struct ClosedLoopRun {
  asg_sim::Termination termination = asg_sim::Termination::kNone;
  std::string collision_with;
  std::vector<asg_sim::TrajectorySample> trajectory;
  uint32_t plans = 0, frames = 0;
};

/// The ground-truth stack as the run loop's stack side: frames voted, commands from the planner.
class GroundTruthStack : public asg_sim::LoopStack {
 public:
  GroundTruthStack(asg_sim::ScenarioRunner* runner, const asg_sim::CameraModel& cam, VotingPlanner* planner)
      : runner_(runner), planner_(planner), K_{cam.fx(), cam.fy(), cam.cx(), cam.cy()} {}
  void onCamera(double t) override {
    runner_->renderCamera(true, &frame_);
    planner_->addFrame(t, frame_.depth.data.data(), frame_.labels.data.data(), frame_.depth.width,
                       frame_.depth.height, K_, runner_->cameraPose());
  }
  bool onControl(double t, asg_sim::Command* cmd, bool* /*apply*/, std::string* /*error*/) override {
    const auto& st = runner_->state();
    VehicleState2D s;
    s.x = st.position.x();
    s.y = st.position.y();
    s.yaw = st.yaw();
    s.speed = st.linear.x();
    const ControlCommand c = planner_->tick(t, s);
    cmd->throttle = c.throttle;
    cmd->steering = c.steering;
    cmd->brake = c.brake;
    cmd->target_speed = c.target_speed;
    return true;
  }

 private:
  asg_sim::ScenarioRunner* runner_;
  VotingPlanner* planner_;
  Intrinsics K_;
  asg_sim::CameraFrame frame_;
};

/// Runs one scenario to its termination with ground-truth labels (a renderer is required).
inline ClosedLoopRun runGroundTruthStack(asg_sim::ScenarioRunner* runner, asg_sim::Renderer* renderer,
                                         const asg_sim::SceneSpec& spec, const PlannerParams& params) {
  runner->reset(spec);
  VotingPlanner planner(params);
  const auto& op = spec.operational;
  planner.reset({op.goal_x, op.goal_y, op.goal_radius, spec.landscape.size, op.speed});
  GroundTruthStack stack(runner, renderer->camera(), &planner);
  ClosedLoopRun out;
  out.termination = asg_sim::runLoop(runner, &stack).termination;
  out.collision_with = runner->collisionWith();
  out.trajectory = runner->trajectory();
  out.plans = planner.plans();
  out.frames = planner.frames();
  return out;
}

}  // namespace asg_planner_harness
