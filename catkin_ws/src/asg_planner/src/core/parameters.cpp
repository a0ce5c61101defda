#include "asg_planner/parameters.hpp"

#include <stdexcept>

namespace asg_planner {
namespace {

using K = asg_lockstep::params::Kind;

#define ASG_FIELD(field) ASG_PARAM_NUMBER(PlannerParams, field)
#define ASG_FLAG(field) ASG_PARAM_FLAG(PlannerParams, field)

// Rows: name, kind, unit, lo, hi, open (never here), range text, description, get/set, then the
// only numbers allowed where a row has them.
const PlannerTable kTable = {
    {"vote_spacing", K::kReal, "m", 0.1, 100, false, "0.1..100", "vote-grid spacing (later code: 1.0)",
     ASG_FIELD(vote_spacing)},
    {"max_votes", K::kInt, "-", 1, 4294967295.0, false, ">= 1", "cap per vertex", ASG_FIELD(max_votes)},
    {"first_plan_delay", K::kReal, "s (sim)", 0, 60, false, "0..60", "first plan after the first frame",
     ASG_FIELD(first_plan_delay)},
    {"replan_period", K::kReal, "s (sim)", 0.05, 60, false, "0.05..60", "time between plans", ASG_FIELD(replan_period)},
    {"astar/vehicle_spacing", K::kReal, "m", 0.1, 100, false, "0.1..100", "vehicle-grid spacing (later code: 2.0)",
     ASG_FIELD(astar.vehicle_spacing)},
    {"astar/alpha", K::kReal, "-", 0, 100, false, "0..100", "cost per vote", ASG_FIELD(astar.alpha)},
    {"astar/sigma", K::kReal, "m", 0.01, 100, false, "0.01..100", "vote influence (later code: 1.5)",
     ASG_FIELD(astar.sigma)},
    {"astar/kernel_sigmas", K::kReal, "-", 1, 10, false, "1..10", "cut-off of the vote kernel",
     ASG_FIELD(astar.kernel_sigmas)},
    {"astar/edge_points", K::kInt, "-", 1, 3, false, "1 or 3",
     "kernel at the edge midpoint (1) or mean of both ends and midpoint (3)", ASG_FIELD(astar.edge_points),
     {}, {1.0, 3.0}},
    {"projection/max_height", K::kReal, "m", -100, 100, false, "-100..100", "higher points do not vote",
     ASG_FIELD(projection.max_height)},
    {"projection/height_above_ground", K::kBool, "-", 0, 1, false, "bool",
     "false: `max_height` is a map z (flat ground); true: a height above the planner's own ground estimate "
     "(terrain)",
     ASG_FLAG(projection.height_above_ground)},
    {"projection/ground_cell", K::kReal, "m", 0.1, 100, false, "0.1..100", "cell of that ground estimate",
     ASG_FIELD(projection.ground_cell)},
    {"projection/max_range", K::kReal, "m", -1, 10000, false, "-1..10000", "planar depth limit, -1: none",
     ASG_FIELD(projection.max_range)},
    {"projection/stride", K::kInt, "px", 1, 64, false, "1..64", "pixel step in u and v", ASG_FIELD(projection.stride)},
    {"follower/lookahead", K::kReal, "m", 0.1, 100, false, "0.1..100", "look-ahead distance", ASG_FIELD(follower.lookahead)},
    {"follower/first_crossing", K::kBool, "-", 0, 1, false, "bool",
     "aim at the first exit from the look-ahead circle (reference) instead of the furthest crossing",
     ASG_FLAG(follower.first_crossing)},
    {"follower/kp", K::kReal, "deg/rad", 0, 10000, false, "0..10000", "front-wheel angle per radian of heading error",
     ASG_FIELD(follower.kp)},
    {"follower/kd", K::kReal, "deg s/rad", 0, 10000, false, "0..10000", "front-wheel angle per rad/s of error rate",
     ASG_FIELD(follower.kd)},
    {"follower/steering_lock", K::kReal, "rad", 0.01, 1.5, false, "0.01..1.5",
     "wheel angle at full command (the vehicle's `max_steer`)", ASG_FIELD(follower.steering_lock)},
    {"follower/derivative_tau", K::kReal, "s", 0, 10, false, "0..10", "low-pass of the error rate, 0: raw (reference)",
     ASG_FIELD(follower.derivative_tau)},
    {"follower/speed_kp", K::kReal, "1/(m/s)", 0, 100, false, "0..100", "throttle per m/s of speed error",
     ASG_FIELD(follower.speed_kp)},
    {"follower/speed_ki", K::kReal, "1/m", 0, 100, false, "0..100", "throttle per metre of integrated error",
     ASG_FIELD(follower.speed_ki)},
    {"follower/brake_gain", K::kReal, "1/(m/s)", 0, 100, false, "0..100", "brake per m/s over the target (beyond 0.3 m/s)",
     ASG_FIELD(follower.brake_gain)},
};

#undef ASG_FIELD
#undef ASG_FLAG

}  // namespace

const PlannerTable& plannerParameters() { return kTable; }

const ParameterSpec& parameterSpec(const std::string& name) {
  const ParameterSpec* s = asg_lockstep::params::find(kTable, name);
  if (!s) throw std::invalid_argument("unknown planner parameter '" + name + "'");
  return *s;
}

double parameterValue(const ParameterSpec& spec, const PlannerParams& params) { return spec.get(&params).number; }

std::string formatValue(const ParameterSpec& spec, double value) {
  asg_lockstep::params::Value v;
  v.number = value;
  return asg_lockstep::params::formatValue(spec.kind, v);
}

void setParameter(PlannerParams* params, const std::string& name, double value) {
  asg_lockstep::params::Value v;
  v.number = value;
  const std::string why = asg_lockstep::params::set(kTable, params, parameterSpec(name), v,
                                                    "planner parameter '" + name + "'");
  if (!why.empty()) throw std::invalid_argument(why);
}

std::string parameterTableMarkdown() { return asg_lockstep::params::markdown(kTable); }

}  // namespace asg_planner
