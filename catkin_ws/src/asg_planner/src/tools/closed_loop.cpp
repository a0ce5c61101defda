// asg_closed_loop: scenarios through the ground-truth-label stack in one process, no ROS
// (closed_loop.hpp), for quick studies of the planner and follower on the real vehicle model.
//   asg_closed_loop [--planner planner.yaml] [--set follower/kp=10 ...] [--out DIR] SCENARIO.yaml...
// Prints one JSON line per scenario (termination, simulated time, obstacle hit, visibility,
// removed obstacles); with --out, DIR/NAME.csv holds the trajectory (t, x, y, yaw, yaw rate).
// Set LP_NUM_THREADS=1 for one core.
#include <yaml-cpp/yaml.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "closed_loop.hpp"
#include "asg_sim/scene_yaml.hpp"

using namespace asg_planner;

namespace {

// key -> where it lives in PlannerParams; the same names as the planner node's parameters.
void setParam(PlannerParams* p, const std::string& key, double v) {
  std::map<std::string, double*> d = {
      {"vote_spacing", &p->vote_spacing},          {"first_plan_delay", &p->first_plan_delay},
      {"replan_period", &p->replan_period},        {"astar/vehicle_spacing", &p->astar.vehicle_spacing},
      {"astar/alpha", &p->astar.alpha},            {"astar/sigma", &p->astar.sigma},
      {"astar/kernel_sigmas", &p->astar.kernel_sigmas}, {"projection/max_height", &p->projection.max_height},
      {"projection/max_range", &p->projection.max_range}, {"projection/ground_cell", &p->projection.ground_cell},
      {"follower/lookahead", &p->follower.lookahead},
      {"follower/kp", &p->follower.kp},            {"follower/kd", &p->follower.kd},
      {"follower/steering_lock", &p->follower.steering_lock},
      {"follower/derivative_tau", &p->follower.derivative_tau}, {"follower/speed_kp", &p->follower.speed_kp},
      {"follower/speed_ki", &p->follower.speed_ki}, {"follower/brake_gain", &p->follower.brake_gain}};
  if (key == "max_votes") p->max_votes = uint32_t(v);
  else if (key == "astar/edge_points") p->astar.edge_points = int(v);
  else if (key == "projection/stride") p->projection.stride = int(v);
  else if (key == "follower/first_crossing") p->follower.first_crossing = v != 0;
  else if (key == "projection/height_above_ground") p->projection.height_above_ground = v != 0;
  else if (d.count(key)) *d[key] = v;
  else if (key == "ack_name" || key == "publish_markers") return;
  else throw std::runtime_error("unknown planner parameter '" + key + "'");
}

void loadYaml(PlannerParams* p, const YAML::Node& n, const std::string& prefix) {
  for (const auto& kv : n) {
    const std::string key = prefix + kv.first.as<std::string>();
    if (kv.second.IsMap()) loadYaml(p, kv.second, key + "/");
    else if (key == "follower/first_crossing") p->follower.first_crossing = kv.second.as<bool>();
    else if (key == "projection/height_above_ground") p->projection.height_above_ground = kv.second.as<bool>();
    else if (key != "ack_name" && key != "publish_markers") setParam(p, key, kv.second.as<double>());
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
        setParam(&params, kv.substr(0, eq), std::stod(kv.substr(eq + 1)));
      } else if (a == "--out" && i + 1 < argc) out_dir = argv[++i];
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
