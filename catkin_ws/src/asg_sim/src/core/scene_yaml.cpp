#include "asg_sim/scene_yaml.hpp"

#include <yaml-cpp/yaml.h>

namespace asg_sim {
namespace {

template <class T>
void get(const YAML::Node& node, const char* key, T* out, const std::string& where, bool required) {
  const YAML::Node v = node[key];
  if (!v) {
    if (required) throw SceneError(where + "." + key + ": missing required field");
    return;
  }
  try {
    *out = v.as<T>();
  } catch (const YAML::Exception&) {
    throw SceneError(where + "." + key + ": wrong type");
  }
}

}  // namespace

ScenarioFile loadScenarioYaml(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw SceneError(path + ": " + e.what());
  }
  ScenarioFile f;
  get(root, "scenario_id", &f.scenario_id, path, false);
  get(root, "record_labels", &f.record_labels, path, false);
  get(root, "name", &f.name, path, false);
  const auto st = root["structural"];
  const auto ld = st["landscape"];
  auto& s = f.spec;
  const std::string lw = path + ": structural.landscape";
  get(ld, "size", &s.landscape.size, lw, true);
  get(ld, "subdivisions", &s.landscape.subdivisions, lw, false);
  get(ld, "border", &s.landscape.border, lw, false);
  if (st["layouts"]) {
    for (size_t i = 0; i < st["layouts"].size(); ++i) {
      const auto l = st["layouts"][i];
      const std::string w = path + ": structural.layouts[" + std::to_string(i) + "]";
      ObstacleLayout layout;
      get(l, "mesh_name", &layout.mesh_name, w, true);
      for (size_t j = 0; l["instances"] && j < l["instances"].size(); ++j) {
        const auto n = l["instances"][j];
        const std::string iw = w + ".instances[" + std::to_string(j) + "]";
        ObstacleInstance inst;
        get(n, "visible", &inst.visible, iw, false);
        get(n, "cast_shadow", &inst.cast_shadow, iw, false);
        get(n, "x", &inst.x, iw, true);
        get(n, "y", &inst.y, iw, true);
        get(n, "yaw", &inst.yaw, iw, false);
        get(n, "scale", &inst.scale, iw, false);
        layout.instances.push_back(inst);
      }
      s.layouts.push_back(layout);
    }
  }
  const auto tx = root["textural"];
  const std::string tw = path + ": textural";
  get(tx, "sun_inclination_deg", &s.textural.sun_inclination_deg, tw, true);
  get(tx, "sun_yaw_deg", &s.textural.sun_yaw_deg, tw, false);
  get(tx, "ground_texture_seed", &s.textural.ground_texture_seed, tw, false);
  const auto op = root["operational"];
  const std::string ow = path + ": operational";
  auto& o = s.operational;
  get(op, "start_x", &o.start_x, ow, true);
  get(op, "start_y", &o.start_y, ow, true);
  get(op, "start_yaw", &o.start_yaw, ow, false);
  get(op, "goal_x", &o.goal_x, ow, true);
  get(op, "goal_y", &o.goal_y, ow, true);
  get(op, "goal_radius", &o.goal_radius, ow, false);
  get(op, "safety_radius", &o.safety_radius, ow, false);
  get(op, "speed", &o.speed, ow, false);
  get(op, "sim_timeout", &o.sim_timeout, ow, false);
  get(op, "idle_timeout", &o.idle_timeout, ow, false);
  get(op, "stuck_timeout", &o.stuck_timeout, ow, false);
  get(op, "max_roll_deg", &o.max_roll_deg, ow, false);
  get(op, "max_pitch_deg", &o.max_pitch_deg, ow, false);
  get(op, "allow_collisions", &o.allow_collisions, ow, false);
  validateScene(s);
  return f;
}

}  // namespace asg_sim
