#pragma once
/// @file planner_options.hpp
/// The planner's parameters for the harness's tools, through the planner's one table
/// (asg_planner/parameters.hpp): `--planner FILE` (planner.yaml or an overlay of it, read in
/// order on top of the defaults) and `--set KEY=VALUE` (a table key, e.g. follower/kp=10). A key
/// outside the table or a value outside its range throws, naming both.

#include <string>
#include <vector>

#include "asg_planner/voting_planner.hpp"

namespace asg_planner_harness {

/// Keys of the planner node that change what it shows, not what it decides: accepted, ignored.
bool displayOnly(const std::string& key);

/// A planner YAML file on top of `p`.
void loadPlannerYaml(asg_planner::PlannerParams* p, const std::string& path);

/// One KEY=VALUE on top of `p` (true/false for flags).
void setPlannerValue(asg_planner::PlannerParams* p, const std::string& key_value);

/// Takes the planner options out of argv[1..argc): `--planner FILE` and `--set KEY=VALUE`, applied
/// in order onto `p`; returns the other arguments, in order.
std::vector<std::string> takePlannerOptions(int argc, char** argv, asg_planner::PlannerParams* p);

}  // namespace asg_planner_harness
