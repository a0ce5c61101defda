#pragma once
/// @file parameters.hpp
/// The planner's parameter table: one row per parameter of PlannerParams (name as the ROS node
/// reads it, kind, unit, range, meaning). The node (planner_ros.cpp), the closed-loop tool and the
/// docs (docs/planner.md's table is checked against `asg_closed_loop --params`) all read it, so a
/// parameter, its unit and its range are written here once. Defaults are PlannerParams' own.
/// No ROS.

#include <string>
#include <vector>

#include "asg_lockstep/param_table.hpp"
#include "asg_planner/voting_planner.hpp"

namespace asg_planner {

/// A row of the table: asg_lockstep's table helper, which every C++ node uses (param_table.hpp).
using ParameterSpec = asg_lockstep::params::Row;
using PlannerTable = asg_lockstep::params::Table<PlannerParams>;

/// Every planner parameter, in the order of planner.yaml.
const PlannerTable& plannerParameters();

/// The row of `name`; throws std::invalid_argument naming an unknown parameter.
const ParameterSpec& parameterSpec(const std::string& name);

/// The row's value in `params` (bools as 0/1).
double parameterValue(const ParameterSpec& spec, const PlannerParams& params);

/// Sets `name` to `value` after checking its kind and range; throws std::invalid_argument that
/// names the parameter, the value and what it must be.
void setParameter(PlannerParams* params, const std::string& name, double value);

/// The value as the docs write it ("5.0", "3", "false").
std::string formatValue(const ParameterSpec& spec, double value);

/// docs/planner.md's parameter table (header and one row per parameter), from the table above
/// and the defaults of PlannerParams.
std::string parameterTableMarkdown();

}  // namespace asg_planner
