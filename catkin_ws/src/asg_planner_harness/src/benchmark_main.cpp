// asg_planner_benchmark: vote insertion per camera frame and A* per replan, on frames rendered
// by the simulator along the start -> goal line of a scenario (ground-truth labels).
//   asg_planner_benchmark [--planner planner.yaml] [--set KEY=VALUE ...] [--frames 150] [--repeats 5]
//       SCENARIO.yaml
// The planner's parameters come from its table (the defaults, then each --planner file and --set
// in order): the grids are vote_spacing and astar/vehicle_spacing, the kernel astar/sigma and
// astar/edge_points (planner_fine.yaml: the finer grids of the authors' later code).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include <stdexcept>
#include <string>

#include "asg_planner/voting_planner.hpp"
#include "asg_planner_harness/planner_options.hpp"
#include "asg_sim/renderer.hpp"
#include "asg_sim/scenario_runner.hpp"
#include "asg_sim/scene_yaml.hpp"

using Clock = std::chrono::steady_clock;

static double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

int main(int argc, char** argv) {
  asg_planner::PlannerParams params;
  int frames = 150, repeats = 5;
  std::string scene;
  try {
    const auto rest = asg_planner_harness::takePlannerOptions(argc, argv, &params);
    for (size_t i = 0; i < rest.size(); ++i) {
      const std::string& a = rest[i];
      if ((a == "--frames" || a == "--repeats") && i + 1 < rest.size()) {
        (a == "--frames" ? frames : repeats) = std::atoi(rest[++i].c_str());
      } else if (!a.empty() && a[0] == '-') {
        throw std::runtime_error("unknown option " + a);
      } else if (scene.empty()) {
        scene = a;
      } else {
        throw std::runtime_error("one scenario file, not " + scene + " and " + a);
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
  if (scene.empty()) {
    std::fprintf(stderr, "usage: %s [--planner planner.yaml] [--set KEY=VALUE] [--frames 150] [--repeats 5] "
                 "SCENARIO.yaml\n", argv[0]);
    return 2;
  }
  if (frames < 1 || repeats < 1) {
    std::fprintf(stderr, "error: --frames and --repeats must be >= 1\n");
    return 2;
  }
  const double vote_spacing = params.vote_spacing, vehicle_spacing = params.astar.vehicle_spacing;
  const double sigma = params.astar.sigma;
  const int edge_points = params.astar.edge_points;
  try {
    const auto f = asg_sim::loadScenarioYaml(scene);
    asg_sim::Renderer renderer;
    asg_sim::ScenarioRunner runner(&renderer);
    runner.reset(f.spec);
    const auto& op = f.spec.operational;
    // Render the frames once.
    std::vector<asg_sim::CameraFrame> shots(frames);
    std::vector<Eigen::Isometry3d> poses(frames);
    for (int i = 0; i < frames; ++i) {
      const double a = double(i) / frames;
      Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
      base.translation() << op.start_x + a * (op.goal_x - op.start_x), op.start_y + a * (op.goal_y - op.start_y), 0;
      const double yaw = std::atan2(op.goal_y - op.start_y, op.goal_x - op.start_x) + 0.5 * std::sin(i * 0.07);
      base.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      poses[i] = base * asg_sim::cameraMount(1.5, 0, 1.4);
      renderer.renderCamera(poses[i], true, &shots[i]);
    }
    const auto& cam = renderer.camera();
    asg_planner::Intrinsics K{cam.fx(), cam.fy(), cam.cx(), cam.cy()};
    std::vector<double> vote_ms, plan_ms, worst_ms;
    // Worst case: every pixel labelled non-traversable (a perception that sees obstacles everywhere).
    std::vector<uint8_t> all_obstacle(size_t(cam.width) * cam.height, 1);
    size_t voters = 0, vertices = 0, expansions = 0;
    for (int rep = 0; rep < repeats; ++rep) {
      asg_planner::VotingPlanner planner(params);
      planner.reset({op.goal_x, op.goal_y, op.goal_radius, f.spec.landscape.size, op.speed});
      const auto t0 = Clock::now();
      for (int i = 0; i < frames; ++i)
        voters += planner.addFrame(i / 15.0, shots[i].depth.data.data(), shots[i].labels.data.data(),
                                   cam.width, cam.height, K, poses[i]);
      vote_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count() / frames);
      vertices = planner.votes().voted().size();
      asg_planner::VotingPlanner worst(params);
      worst.reset({op.goal_x, op.goal_y, op.goal_radius, f.spec.landscape.size, op.speed});
      const auto tw = Clock::now();
      for (int i = 0; i < frames; ++i)
        worst.addFrame(i / 15.0, shots[i].depth.data.data(), all_obstacle.data(), cam.width, cam.height, K, poses[i]);
      worst_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - tw).count() / frames);
      const auto t1 = Clock::now();
      const int plans = 20;
      for (int k = 0; k < plans; ++k) {
        const auto p = asg_planner::planPath(planner.votes(), params.astar, f.spec.landscape.size,
                                             Eigen::Vector2d(op.start_x + k, op.start_y), Eigen::Vector2d(op.goal_x, op.goal_y));
        expansions = p.expansions;
      }
      plan_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t1).count() / plans);
    }
    std::printf("scene %s, vote grid %.1f m, vehicle grid %.1f m, sigma %.1f m, %d edge point(s), %d frames x %d "
                "repeats, medians:\n", f.name.c_str(), vote_spacing, vehicle_spacing, sigma, edge_points, frames, repeats);
    std::printf("  vote insertion        %8.3f ms/frame (%.0f voting pixels/frame, %zu voted vertices)\n",
                median(vote_ms), double(voters) / (frames * repeats), vertices);
    std::printf("  vote insertion, every pixel an obstacle %8.3f ms/frame\n", median(worst_ms));
    std::printf("  A* replan             %8.3f ms/plan (%zu expansions)\n", median(plan_ms), expansions);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
