#pragma once
/// @file scene_yaml.hpp
/// Reads a scenario YAML file (docs/scenario-format.md) into a SceneSpec for C++ tools and
/// tests. The Python validator (asg_scenario) is the reference for defaults; validateScene()
/// checks ranges here.

#include <string>

#include "asg_sim/scene.hpp"

namespace asg_sim {

struct ScenarioFile {
  SceneSpec spec;
  uint32_t scenario_id = 1;
  bool record_labels = true;
  std::string name;
};

/// Throws SceneError naming the file and the field on a missing or mistyped field.
ScenarioFile loadScenarioYaml(const std::string& path);

}  // namespace asg_sim
