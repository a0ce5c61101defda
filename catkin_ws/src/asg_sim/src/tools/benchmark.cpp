// asg_sim_benchmark: prints the simulator's cost figures (docs/benchmarks.md).
//   asg_sim_benchmark SCENARIO.yaml [frames] [repeats]
// Render cost per camera frame (RGB + depth, and with labels), shadow pass per scene, physics
// cost per tick, and the speed of a whole run with a scripted driver and cameras on
// (simulated seconds per wall second). Medians over repeats. Set LP_NUM_THREADS=1 for one core.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "asg_sim/renderer.hpp"
#include "asg_sim/run_loop.hpp"
#include "asg_sim/scenario_runner.hpp"
#include "asg_sim/scene_yaml.hpp"

using namespace asg_sim;
using Clock = std::chrono::steady_clock;

static double ms(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}
static double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

// Constant-throttle driver steering towards the goal: the scripted stand-in for a stack.
static Command scripted(const ScenarioRunner& r) {
  const auto& op = r.spec().operational;
  const auto& s = r.state();
  double err = std::atan2(op.goal_y - s.position.y(), op.goal_x - s.position.x()) - s.yaw();
  err = std::atan2(std::sin(err), std::cos(err));
  Command c;
  c.target_speed = op.speed;
  c.steering = std::clamp(2.0 * err, -1.0, 1.0);
  const double v = s.linear.x();
  c.throttle = v < op.speed ? std::clamp(0.5 * (op.speed - v) + 0.1, 0.0, 1.0) : 0.0;
  c.brake = v > op.speed + 0.5 ? 0.3 : 0.0;
  return c;
}

// The scripted driver as the run loop's stack side; `frame` null: no camera renders; `max_ticks`
// > 0 ends the run there (as ERROR, which the physics-only timing ignores).
class ScriptedStack : public LoopStack {
 public:
  ScriptedStack(ScenarioRunner* r, CameraFrame* frame, bool labels, uint64_t max_ticks)
      : r_(r), frame_(frame), labels_(labels), max_ticks_(max_ticks) {}
  void onCamera(double) override {
    if (frame_) r_->renderCamera(labels_, frame_);
  }
  bool onControl(double, Command* cmd, bool*, std::string*) override {
    *cmd = scripted(*r_);
    return true;
  }
  bool afterStep(std::string*) override { return max_ticks_ == 0 || r_->tick() < max_ticks_; }

 private:
  ScenarioRunner* r_;
  CameraFrame* frame_;
  bool labels_;
  uint64_t max_ticks_;
};

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s SCENARIO.yaml [frames=200] [repeats=5]\n", argv[0]);
    return 2;
  }
  const int frames = argc > 2 ? std::atoi(argv[2]) : 200;
  const int repeats = argc > 3 ? std::atoi(argv[3]) : 5;
  try {
    const ScenarioFile f = loadScenarioYaml(argv[1]);
    Renderer renderer;
    ScenarioRunner runner(&renderer);
    std::vector<double> build, shadow, plain, labelled, physics, rate;
    const Terrain terrain(f.spec.terrain);
    CameraFrame frame;
    for (int rep = 0; rep < repeats; ++rep) {
      const auto tb = Clock::now();
      runner.reset(f.spec);  // the scene build: placement, ground mesh, shadow and footprint maps, Bullet world
      build.push_back(ms(tb, Clock::now()));
      shadow.push_back(renderer.lastShadowPassMs());
      // Camera poses along the start -> goal line (what a run sees).
      const auto& op = f.spec.operational;
      std::vector<Eigen::Isometry3d> poses;
      for (int i = 0; i < frames; ++i) {
        const double a = double(i) / frames;
        Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
        const double yaw = std::atan2(op.goal_y - op.start_y, op.goal_x - op.start_x) + 0.3 * std::sin(i * 0.1);
        const double x = op.start_x + a * (op.goal_x - op.start_x), y = op.start_y + a * (op.goal_y - op.start_y);
        base.translation() << x, y, terrain.height(x, y);  // on the ground (level: the frame cost, not the view)
        base.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
        poses.push_back(base * cameraMount(1.5, 0, 1.4));
      }
      auto t0 = Clock::now();
      for (const auto& p : poses) renderer.renderCamera(p, false, &frame);
      auto t1 = Clock::now();
      for (const auto& p : poses) renderer.renderCamera(p, true, &frame);
      auto t2 = Clock::now();
      plain.push_back(ms(t0, t1) / frames);
      labelled.push_back(ms(t1, t2) / frames);

      // Physics only (the first 600 ticks at most).
      ScenarioRunner phys(nullptr);
      phys.reset(f.spec);
      auto t3 = Clock::now();
      ScriptedStack physics_only(&phys, nullptr, false, 600);
      runLoop(&phys, &physics_only);
      physics.push_back(ms(t3, Clock::now()) / std::max<double>(1.0, double(phys.tick())));

      // Whole run: scripted driver, cameras at 15 Hz with labels (as the worker runs it), through
      // the worker's run loop.
      runner.reset(f.spec);
      auto t4 = Clock::now();
      ScriptedStack driver(&runner, &frame, f.record_labels, 0);
      const Termination term = runLoop(&runner, &driver).termination;
      const double wall = ms(t4, Clock::now()) / 1000.0;
      rate.push_back(runner.time() / wall);
      if (rep == 0)
        std::printf("scripted run: %s after %.2f s simulated, %zu samples\n", terminationName(term),
                    runner.time(), runner.trajectory().size());
    }
    std::printf("scene: %s (%zu obstacles placed), %d frames x %d repeats, medians:\n",
                f.name.c_str(), runner.placed().size(), frames, repeats);
    std::printf("  scene build (reset)               %8.2f ms\n", median(build));
    std::printf("  shadow pass (once per scene)      %8.2f ms\n", median(shadow));
    std::printf("  camera RGB + depth                %8.2f ms/frame\n", median(plain));
    std::printf("  camera RGB + depth + labels       %8.2f ms/frame\n", median(labelled));
    std::printf("  physics tick (60 Hz, 2 substeps)  %8.3f ms/tick\n", median(physics));
    std::printf("  scripted run, cameras on          %8.1f simulated s per wall s\n", median(rate));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
