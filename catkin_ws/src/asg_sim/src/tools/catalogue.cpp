// Prints the C++ mesh catalogue as YAML (compared with asg_scenario's in a test).
#include <cstdio>

#include "asg_sim/meshes.hpp"

int main() {
  for (const auto& m : asg_sim::meshCatalogue())
    std::printf("%s: {height: %.3f, collision_radius: %.3f, shadow_opacity: %.3f}\n", m.name.c_str(),
                m.height, m.collision_radius, m.shadow_opacity);
  return 0;
}
