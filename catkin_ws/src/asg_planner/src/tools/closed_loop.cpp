// asg_closed_loop: scenarios through the ground-truth-label stack in one process, no ROS
// (closed_loop.hpp), for quick studies of the planner and follower on the real vehicle model.
//   asg_closed_loop [--planner planner.yaml] [--set follower/kp=10 ...] [--out DIR] SCENARIO.yaml...
//   asg_closed_loop --params      (the parameter table, Markdown: docs/planner.md)
// --planner files are read in order on top of the planner's defaults (a variant is an overlay).
// Prints one JSON line per scenario (termination, simulated time, obstacle hit, visibility,
// removed obstacles); with --out, DIR/NAME.csv holds the trajectory (t, x, y, yaw, yaw rate).
// Set LP_NUM_THREADS=1 for one core.
#include <yaml-cpp/yaml.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "asg_planner/parameters.hpp"
#include "closed_loop.hpp"
#include "asg_sim/scene_yaml.hpp"

using namespace asg_planner;

namespace {

// Parameters of the planner node that change what it shows, not what it decides: ignored here.
bool displayOnly(const std::string& key) { return key == "ack_name" || key == "publish_markers"; }

// A planner YAML (planner.yaml, or an overlay of it) on top of `p`, through the planner's table.
void loadYaml(PlannerParams* p, const YAML::Node& n, const std::string& prefix) {
  for (const auto& kv : n) {
    const std::string key = prefix + kv.first.as<std::string>();
    if (kv.second.IsMap()) loadYaml(p, kv.second, key + "/");
    else if (displayOnly(key)) continue;
    else if (parameterSpec(key).kind == ParameterSpec::kBool) setParameter(p, key, kv.second.as<bool>());
    else setParameter(p, key, kv.second.as<double>());
  }
}

}  // namespace

int main(int argc, char** argv) {
  PlannerParams params;
  std::string out_dir;
  std::vector<std::string> files;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "--planner" && i + 1 < argc) loadYaml(&params, YAML::LoadFile(argv[++i]), "");
      else if (a == "--set" && i + 1 < argc) {
        const std::string kv = argv[++i];
        const auto eq = kv.find('=');
        if (eq == std::string::npos) throw std::runtime_error("--set " + kv + ": expected KEY=VALUE");
        const std::string key = kv.substr(0, eq), value = kv.substr(eq + 1);
        if (displayOnly(key)) continue;
        const bool flag = parameterSpec(key).kind == ParameterSpec::kBool && (value == "true" || value == "false");
        setParameter(&params, key, flag ? double(value == "true") : std::stod(value));
      } else if (a == "--out" && i + 1 < argc) out_dir = argv[++i];
      else if (a == "--params") {  // the planner's parameter table, as docs/planner.md shows it
        std::fputs(parameterTableMarkdown().c_str(), stdout);
        return 0;
      }
      else if (!a.empty() && a[0] == '-') throw std::runtime_error("unknown option " + a);
      else files.push_back(a);
    }
    if (files.empty()) {
      std::fprintf(stderr, "usage: %s [--planner planner.yaml] [--set KEY=VALUE] [--out DIR] SCENARIO.yaml...\n",
                   argv[0]);
      return 2;
    }
    asg_sim::Renderer renderer;
    asg_sim::ScenarioRunner runner(&renderer);
    for (const auto& path : files) {
      const asg_sim::ScenarioFile f = asg_sim::loadScenarioYaml(path);
      const ClosedLoopRun r = runGroundTruthStack(&runner, &renderer, f.spec, params);
      std::string vis, removed;
      for (float v : runner.obstacleVisibility()) vis += (vis.empty() ? "" : ",") + std::to_string(v);
      for (const auto& o : runner.removed())
        removed += std::string(removed.empty() ? "" : ",") + "[" + std::to_string(o.layout_index) + "," +
                   std::to_string(o.instance_index) + ",\"" + o.reason + "\"]";
      std::printf("{\"file\": \"%s\", \"name\": \"%s\", \"termination\": \"%s\", \"sim_time\": %.4f, "
                  "\"collision_with\": \"%s\", \"plans\": %u, \"visibility\": [%s], \"removed\": [%s]}\n",
                  path.c_str(), f.name.c_str(), asg_sim::terminationName(r.termination), runner.time(),
                  r.collision_with.c_str(), r.plans, vis.c_str(), removed.c_str());
      std::fflush(stdout);
      if (!out_dir.empty()) {
        std::ofstream csv(out_dir + "/" + f.name + ".csv");
        csv << "t,x,y,yaw,yaw_rate\n";
        char line[160];
        for (const auto& s : r.trajectory) {
          std::snprintf(line, sizeof(line), "%.5f,%.5f,%.5f,%.6f,%.6f\n", s.t, s.state.position.x(),
                        s.state.position.y(), s.state.yaw(), s.state.angular.z());
          csv << line;
        }
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
