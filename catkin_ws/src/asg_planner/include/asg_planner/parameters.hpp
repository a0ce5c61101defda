#pragma once
/// @file parameters.hpp
/// The planner's parameter table: one row per parameter of PlannerParams (name as the ROS node
/// reads it, kind, unit, range, meaning). The node (planner_ros.cpp), the closed-loop tool and the
/// docs (docs/planner.md's table is checked against `asg_closed_loop --params`) all read it, so a
/// parameter, its unit and its range are written here once. Defaults are PlannerParams' own.
/// No ROS.

#include <string>
#include <vector>

#include "asg_planner/voting_planner.hpp"

namespace asg_planner {

struct ParameterSpec {
  enum Kind { kReal, kInt, kBool };
  const char* name;         ///< as the node reads it, e.g. "follower/kp"
  Kind kind;
  const char* unit;         ///< "-" when dimensionless
  double lo, hi;            ///< inclusive range (bools: 0..1)
  const char* range_text;   ///< the range as the docs write it
  const char* description;  ///< one line for the docs
  double (*get)(const PlannerParams&);
  void (*set)(PlannerParams*, double);  ///< no checks; use setParameter
  std::vector<double> choices = {};     ///< the only values allowed (empty: any in range)
};

/// Every planner parameter, in the order of planner.yaml.
const std::vector<ParameterSpec>& plannerParameters();

/// The row of `name`; throws std::invalid_argument naming an unknown parameter.
const ParameterSpec& parameterSpec(const std::string& name);

/// Sets `name` to `value` after checking its kind and range; throws std::invalid_argument that
/// names the parameter, the value and what it must be.
void setParameter(PlannerParams* params, const std::string& name, double value);

/// The value as the docs write it ("5.0", "3", "false").
std::string formatValue(const ParameterSpec& spec, double value);

/// docs/planner.md's parameter table (header and one row per parameter), from the table above
/// and the defaults of PlannerParams.
std::string parameterTableMarkdown();

}  // namespace asg_planner
