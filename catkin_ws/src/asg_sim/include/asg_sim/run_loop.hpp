#pragma once
/// @file run_loop.hpp
/// The one lockstep run loop (issue #38), used by the scene worker, the planner's closed-loop
/// tool and the simulator benchmark. At each 60 Hz tick, in this order: the vehicle state to the
/// stack (at camera frames and control ticks, or every tick), the camera frame if due, the
/// stack's command if a control tick is due, one physics tick between the stack's before- and
/// after-step hooks.
/// That order is what makes a run repeat bit for bit from its request: every caller runs it.
/// No ROS, no wall clock.

#include <string>

#include "asg_sim/scenario_runner.hpp"

namespace asg_sim {

/// The stack side of a run: a ROS adapter (the scene worker) or a stack in the same process.
class LoopStack {
 public:
  virtual ~LoopStack() = default;
  /// True: onState at every tick, not only at camera frames and control ticks.
  virtual bool stateEveryTick() const { return false; }
  /// The vehicle state at simulated time t [s] (odometry, tf).
  virtual void onState(double /*t*/) {}
  /// A camera frame is due at t [s].
  virtual void onCamera(double /*t*/) {}
  /// A control tick at t [s]. Return true with *apply set to apply *cmd (false: keep the command
  /// in force); return false to end the run as ERROR with *error.
  virtual bool onControl(double t, Command* cmd, bool* apply, std::string* error) = 0;
  /// Just before each physics tick (a stage timer starts here).
  virtual void beforeStep() {}
  /// After each physics tick (pacing, cancel, feedback). Return false to end the run as ERROR
  /// with *error, even when the tick itself ended it.
  virtual bool afterStep(std::string* /*error*/) { return true; }
};

struct LoopEnd {
  Termination termination = Termination::kNone;
  std::string error;  ///< why, when termination is kError
};

/// Runs `runner` (reset to its scene by the caller) until the run terminates.
LoopEnd runLoop(ScenarioRunner* runner, LoopStack* stack);

}  // namespace asg_sim
