#include "asg_planner/parameters.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace asg_planner {
namespace {

using K = ParameterSpec::Kind;

// get/set of one field, as captureless lambdas (function pointers).
#define ASG_FIELD(expr)                                                  \
  [](const PlannerParams& p) { return double(p.expr); },               \
      [](PlannerParams* p, double v) { p->expr = decltype(p->expr)(v); }
#define ASG_FLAG(expr)                                                     \
  [](const PlannerParams& p) { return p.expr ? 1.0 : 0.0; },             \
      [](PlannerParams* p, double v) { p->expr = v != 0.0; }

const std::vector<ParameterSpec> kTable = {
    {"vote_spacing", K::kReal, "m", 0.1, 100, "0.1..100", "vote-grid spacing (later code: 1.0)",
     ASG_FIELD(vote_spacing)},
    {"max_votes", K::kInt, "-", 1, 4294967295.0, ">= 1", "cap per vertex", ASG_FIELD(max_votes)},
    {"first_plan_delay", K::kReal, "s (sim)", 0, 60, "0..60", "first plan after the first frame",
     ASG_FIELD(first_plan_delay)},
    {"replan_period", K::kReal, "s (sim)", 0.05, 60, "0.05..60", "time between plans", ASG_FIELD(replan_period)},
    {"astar/vehicle_spacing", K::kReal, "m", 0.1, 100, "0.1..100", "vehicle-grid spacing (later code: 2.0)",
     ASG_FIELD(astar.vehicle_spacing)},
    {"astar/alpha", K::kReal, "-", 0, 100, "0..100", "cost per vote", ASG_FIELD(astar.alpha)},
    {"astar/sigma", K::kReal, "m", 0.01, 100, "0.01..100", "vote influence (later code: 1.5)",
     ASG_FIELD(astar.sigma)},
    {"astar/kernel_sigmas", K::kReal, "-", 1, 10, "1..10", "cut-off of the vote kernel",
     ASG_FIELD(astar.kernel_sigmas)},
    {"astar/edge_points", K::kInt, "-", 1, 3, "1 or 3",
     "kernel at the edge midpoint (1) or mean of both ends and midpoint (3)", ASG_FIELD(astar.edge_points),
     {1.0, 3.0}},
    {"projection/max_height", K::kReal, "m", -100, 100, "-100..100", "higher points do not vote",
     ASG_FIELD(projection.max_height)},
    {"projection/height_above_ground", K::kBool, "-", 0, 1, "bool",
     "false: `max_height` is a map z (flat ground); true: a height above the planner's own ground estimate "
     "(terrain)",
     ASG_FLAG(projection.height_above_ground)},
    {"projection/ground_cell", K::kReal, "m", 0.1, 100, "0.1..100", "cell of that ground estimate",
     ASG_FIELD(projection.ground_cell)},
    {"projection/max_range", K::kReal, "m", -1, 10000, "-1..10000", "planar depth limit, -1: none",
     ASG_FIELD(projection.max_range)},
    {"projection/stride", K::kInt, "px", 1, 64, "1..64", "pixel step in u and v", ASG_FIELD(projection.stride)},
    {"follower/lookahead", K::kReal, "m", 0.1, 100, "0.1..100", "look-ahead distance", ASG_FIELD(follower.lookahead)},
    {"follower/first_crossing", K::kBool, "-", 0, 1, "bool",
     "aim at the first exit from the look-ahead circle (reference) instead of the furthest crossing",
     ASG_FLAG(follower.first_crossing)},
    {"follower/kp", K::kReal, "deg/rad", 0, 10000, "0..10000", "front-wheel angle per radian of heading error",
     ASG_FIELD(follower.kp)},
    {"follower/kd", K::kReal, "deg s/rad", 0, 10000, "0..10000", "front-wheel angle per rad/s of error rate",
     ASG_FIELD(follower.kd)},
    {"follower/steering_lock", K::kReal, "rad", 0.01, 1.5, "0.01..1.5",
     "wheel angle at full command (the vehicle's `max_steer`)", ASG_FIELD(follower.steering_lock)},
    {"follower/derivative_tau", K::kReal, "s", 0, 10, "0..10", "low-pass of the error rate, 0: raw (reference)",
     ASG_FIELD(follower.derivative_tau)},
    {"follower/speed_kp", K::kReal, "1/(m/s)", 0, 100, "0..100", "throttle per m/s of speed error",
     ASG_FIELD(follower.speed_kp)},
    {"follower/speed_ki", K::kReal, "1/m", 0, 100, "0..100", "throttle per metre of integrated error",
     ASG_FIELD(follower.speed_ki)},
    {"follower/brake_gain", K::kReal, "1/(m/s)", 0, 100, "0..100", "brake per m/s over the target (beyond 0.3 m/s)",
     ASG_FIELD(follower.brake_gain)},
};

#undef ASG_FIELD
#undef ASG_FLAG

}  // namespace

const std::vector<ParameterSpec>& plannerParameters() { return kTable; }

const ParameterSpec& parameterSpec(const std::string& name) {
  for (const auto& s : kTable)
    if (name == s.name) return s;
  throw std::invalid_argument("unknown planner parameter '" + name + "'");
}

std::string formatValue(const ParameterSpec& spec, double value) {
  if (spec.kind == K::kBool) return value != 0.0 ? "true" : "false";
  char buf[64];
  if (spec.kind == K::kInt) {
    std::snprintf(buf, sizeof(buf), "%.0f", value);
    return buf;
  }
  std::snprintf(buf, sizeof(buf), "%.15g", value);
  std::string s = buf;
  if (s.find_first_of(".e") == std::string::npos) s += ".0";
  return s;
}

void setParameter(PlannerParams* params, const std::string& name, double value) {
  const ParameterSpec& s = parameterSpec(name);
  auto fail = [&](const std::string& must) {
    throw std::invalid_argument("planner parameter '" + name + "' = " + formatValue(s, value) + ": must be " +
                                must);
  };
  if (!std::isfinite(value)) fail("a finite number");
  if (s.kind == K::kBool && value != 0.0 && value != 1.0) fail("true or false");
  if (s.kind == K::kInt && value != std::floor(value)) fail("a whole number");
  if (!s.choices.empty()) {
    bool ok = false;
    for (double c : s.choices) ok = ok || value == c;
    if (!ok) fail(s.range_text);
  } else if (!(value >= s.lo && value <= s.hi)) {
    fail(std::string("in ") + s.range_text + (s.unit[0] == '-' ? "" : std::string(" [") + s.unit + "]"));
  }
  s.set(params, value);
}

std::string parameterTableMarkdown() {
  const PlannerParams defaults;
  std::string out = "| parameter | unit | default | range | meaning |\n|---|---|---|---|---|\n";
  for (const auto& s : kTable)
    out += std::string("| `") + s.name + "` | " + s.unit + " | " + formatValue(s, s.get(defaults)) + " | " +
           s.range_text + " | " + s.description + " |\n";
  return out;
}

}  // namespace asg_planner
