#include "asg_planner_harness/planner_options.hpp"

#include <yaml-cpp/yaml.h>

#include <stdexcept>

#include "asg_planner/parameters.hpp"

namespace asg_planner_harness {

using asg_planner::ParameterSpec;
using asg_planner::PlannerParams;

bool displayOnly(const std::string& key) { return key == "ack_name" || key == "publish_markers"; }

namespace {

void loadNode(PlannerParams* p, const YAML::Node& n, const std::string& prefix) {
  for (const auto& kv : n) {
    const std::string key = prefix + kv.first.as<std::string>();
    if (kv.second.IsMap()) loadNode(p, kv.second, key + "/");
    else if (displayOnly(key)) continue;
    else if (asg_planner::parameterSpec(key).kind == asg_lockstep::params::Kind::kBool)
      asg_planner::setParameter(p, key, kv.second.as<bool>());
    else asg_planner::setParameter(p, key, kv.second.as<double>());
  }
}

}  // namespace

void loadPlannerYaml(PlannerParams* p, const std::string& path) {
  YAML::Node n;
  try {
    n = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw std::runtime_error("--planner " + path + ": " + e.what());
  }
  try {
    loadNode(p, n, "");
  } catch (const std::exception& e) {
    throw std::runtime_error("--planner " + path + ": " + e.what());
  }
}

void setPlannerValue(PlannerParams* p, const std::string& kv) {
  const auto eq = kv.find('=');
  if (eq == std::string::npos || eq == 0) throw std::runtime_error("--set " + kv + ": expected KEY=VALUE");
  const std::string key = kv.substr(0, eq), value = kv.substr(eq + 1);
  if (displayOnly(key)) return;
  const bool flag = asg_planner::parameterSpec(key).kind == asg_lockstep::params::Kind::kBool;
  double v = 0.0;
  if (flag && (value == "true" || value == "false")) {
    v = value == "true";
  } else {
    size_t used = 0;
    try {
      v = std::stod(value, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != value.size()) throw std::runtime_error("--set " + kv + ": " + value + " is not a number");
  }
  asg_planner::setParameter(p, key, v);
}

std::vector<std::string> takePlannerOptions(int argc, char** argv, PlannerParams* p) {
  std::vector<std::string> rest;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if ((a == "--planner" || a == "--set") && i + 1 >= argc) throw std::runtime_error(a + " needs a value");
    if (a == "--planner") loadPlannerYaml(p, argv[++i]);
    else if (a == "--set") setPlannerValue(p, argv[++i]);
    else rest.push_back(a);
  }
  return rest;
}

}  // namespace asg_planner_harness
