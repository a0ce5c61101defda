#pragma once
#include "asg_sim/renderer.hpp"
#include "asg_sim/scene.hpp"

// One OSMesa context for the whole test binary, shared by every test file.
inline asg_sim::Renderer& sharedRenderer() {
  static asg_sim::Renderer r;
  return r;
}

// An empty 100 m scene, vehicle at (20, 50) heading +x, goal far to the east.
inline asg_sim::SceneSpec emptyScene() {
  asg_sim::SceneSpec s;
  s.landscape.size = 100.0;
  s.landscape.border = 20.0;
  s.textural.sun_inclination_deg = 30.0;
  s.textural.sun_yaw_deg = 0.0;
  auto& o = s.operational;
  o.start_x = 20.0;
  o.start_y = 50.0;
  o.start_yaw = 0.0;
  o.goal_x = 95.0;
  o.goal_y = 50.0;
  o.goal_radius = 3.0;
  o.safety_radius = 5.0;
  o.sim_timeout = 60.0;
  o.idle_timeout = -1.0;
  o.stuck_timeout = -1.0;
  return s;
}

inline void addObstacle(asg_sim::SceneSpec* s, const std::string& mesh, double x, double y,
                        double scale = 1.0, bool cast_shadow = true) {
  for (auto& l : s->layouts)
    if (l.mesh_name == mesh) {
      l.instances.push_back({true, cast_shadow, x, y, 0.0, scale});
      return;
    }
  s->layouts.push_back({mesh, {{true, cast_shadow, x, y, 0.0, scale}}});
}
