#include "asg_sim/run_loop.hpp"

namespace asg_sim {

LoopEnd runLoop(ScenarioRunner* runner, LoopStack* stack) {
  LoopEnd end;
  while (end.termination == Termination::kNone) {
    const double t = runner->time();
    // The stack reads the state at the stamps of camera frames and control ticks only; the
    // other ticks' states are in the trajectory (stateEveryTick: hand them over anyway).
    if (stack->stateEveryTick() || runner->cameraDue() || runner->controlDue()) stack->onState(t);
    if (runner->cameraDue()) stack->onCamera(t);
    if (runner->controlDue()) {
      Command cmd;
      bool apply = true;
      if (!stack->onControl(t, &cmd, &apply, &end.error)) {
        end.termination = Termination::kError;
        return end;  // before the physics tick: the command for it never came
      }
      if (apply) runner->applyCommand(cmd);
    }
    stack->beforeStep();
    end.termination = runner->step();
    if (!stack->afterStep(&end.error)) end.termination = Termination::kError;
  }
  return end;
}

}  // namespace asg_sim
