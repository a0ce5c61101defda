#pragma once
/// @file closed_loop.hpp
/// The ground-truth-label stack (voting planner + path follower) closed around the simulator
/// core in one process, no ROS: the order of the lockstep protocol (at each 60 Hz tick: camera
/// frame if due, then the control command if due, then one physics tick), so a run follows the
/// same decisions the ROS stack makes. For tools and tests; the planner core itself does not
/// depend on the simulator.

#include <string>
#include <vector>

#include "asg_planner/voting_planner.hpp"
#include "asg_sim/scenario_runner.hpp"

namespace asg_planner {

struct ClosedLoopRun {
  asg_sim::Termination termination = asg_sim::Termination::kNone;
  std::string collision_with;
  std::vector<asg_sim::TrajectorySample> trajectory;
  uint32_t plans = 0, frames = 0;
};

/// Runs one scenario to its termination with ground-truth labels (a renderer is required).
inline ClosedLoopRun runGroundTruthStack(asg_sim::ScenarioRunner* runner, asg_sim::Renderer* renderer,
                                         const asg_sim::SceneSpec& spec, const PlannerParams& params) {
  runner->reset(spec);
  VotingPlanner planner(params);
  const auto& op = spec.operational;
  planner.reset({op.goal_x, op.goal_y, op.goal_radius, spec.landscape.size, op.speed});
  const auto& cam = renderer->camera();
  const Intrinsics K{cam.fx(), cam.fy(), cam.cx(), cam.cy()};
  asg_sim::CameraFrame frame;
  ClosedLoopRun out;
  while (out.termination == asg_sim::Termination::kNone) {
    const double t = runner->time();
    if (runner->cameraDue()) {
      runner->renderCamera(true, &frame);
      planner.addFrame(t, frame.depth.data.data(), frame.labels.data.data(), frame.depth.width,
                       frame.depth.height, K, runner->cameraPose());
    }
    if (runner->controlDue()) {
      const auto& st = runner->state();
      VehicleState2D s;
      s.x = st.position.x();
      s.y = st.position.y();
      s.yaw = st.yaw();
      s.speed = st.linear.x();
      const ControlCommand c = planner.tick(t, s);
      asg_sim::Command cmd;
      cmd.throttle = c.throttle;
      cmd.steering = c.steering;
      cmd.brake = c.brake;
      cmd.target_speed = c.target_speed;
      runner->applyCommand(cmd);
    }
    out.termination = runner->step();
  }
  out.collision_with = runner->collisionWith();
  out.trajectory = runner->trajectory();
  out.plans = planner.plans();
  out.frames = planner.frames();
  return out;
}

}  // namespace asg_planner
