// asg_closed_loop: scenarios through the ground-truth-label stack in one process, no ROS
// (closed_loop.hpp), for quick studies of the planner and follower on the real vehicle model.
//   asg_closed_loop [--planner planner.yaml] [--set follower/kp=10 ...] [--out DIR] SCENARIO.yaml...
//   asg_closed_loop --params      (the parameter table, Markdown: docs/planner.md)
// --planner files are read in order on top of the planner's defaults (a variant is an overlay).
// Prints one JSON line per scenario (termination, simulated time, obstacle hit, visibility,
// removed obstacles); with --out, DIR/NAME.csv holds the trajectory (t, x, y, yaw, yaw rate).
// Set LP_NUM_THREADS=1 for one core.
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "asg_planner/parameters.hpp"
#include "asg_planner_harness/closed_loop.hpp"
#include "asg_planner_harness/planner_options.hpp"
#include "asg_sim/scene_yaml.hpp"

using namespace asg_planner_harness;

int main(int argc, char** argv) {
  PlannerParams params;
  std::string out_dir;
  std::vector<std::string> files;
  try {
    const auto rest = takePlannerOptions(argc, argv, &params);
    for (size_t i = 0; i < rest.size(); ++i) {
      const std::string& a = rest[i];
      if (a == "--out" && i + 1 < rest.size()) {
        out_dir = rest[++i];
      } else if (a == "--params") {  // the planner's parameter table, as docs/planner.md shows it
        std::fputs(asg_planner::parameterTableMarkdown().c_str(), stdout);
        return 0;
      } else if (!a.empty() && a[0] == '-') {
        throw std::runtime_error("unknown option " + a);
      } else {
        files.push_back(a);
      }
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
