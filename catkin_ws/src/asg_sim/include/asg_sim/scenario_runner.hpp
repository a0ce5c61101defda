#pragma once
/// @file scenario_runner.hpp
/// One scenario as a step-by-step state machine: build the scene, step the vehicle at a fixed
/// tick, say when a camera frame and a control command are due, render, check terminations,
/// record the trajectory. The caller (the ROS node, a benchmark, a test) owns the loop, so the
/// lockstep protocol lives outside and this class stays free of ROS and of wall-clock time.

#include "asg_sim/scene_schema.hpp"
#include <Eigen/Geometry>
#include <memory>
#include <string>
#include <vector>

#include "asg_sim/physics.hpp"
#include "asg_sim/renderer.hpp"
#include "asg_sim/scene.hpp"

namespace asg_sim {

/// Termination reasons, same values as asg_msgs/RunScenarioResult.
/// How a run ends: declared once, in the scenario schema (asg_scenario/schema.py TERMINATIONS).
using Termination = schema::Termination;
const char* terminationName(Termination t);

struct RunnerConfig {
  int tick_hz = 60;              ///< [Hz] odometry / trajectory rate (one physics tick)
  int physics_substeps = 2;      ///< [-] fixed Bullet steps per tick (120 Hz)
  int camera_every = 4;          ///< [ticks] 60 / 4 = 15 Hz
  int control_every = 3;         ///< [ticks] 60 / 3 = 20 Hz
  double still_speed = 0.02;     ///< [m/s] idle / stuck threshold
  double visibility_full_px = 100.0;  ///< [px] an obstacle this large in one frame counts as fully seen
  Eigen::Vector3d camera_mount{1.5, 0.0, 1.4};  ///< [m] in base_link
  VehicleParams vehicle;
};

struct TrajectorySample {
  double t;  ///< [s]
  VehicleState state;
};

class ScenarioRunner {
 public:
  /// renderer may be nullptr: no camera (physics-only runs).
  ScenarioRunner(Renderer* renderer, const RunnerConfig& config = RunnerConfig());

  /// Validates and builds the scene; the vehicle rests at the start pose at tick 0.
  /// Throws SceneError for a malformed scene.
  void reset(const SceneSpec& spec);

  uint64_t tick() const { return tick_; }
  double time() const { return double(tick_) / config_.tick_hz; }
  bool cameraDue() const { return renderer_ && tick_ % config_.camera_every == 0; }
  bool controlDue() const { return tick_ % config_.control_every == 0; }
  const VehicleState& state() const { return state_; }
  /// [m/s] planar displacement over the last tick / tick length (idle and stuck use it)
  double groundSpeed() const { return ground_speed_; }

  /// Renders the camera at the current state; with labels, updates per-obstacle visibility.
  void renderCamera(bool with_labels, CameraFrame* out);
  /// T_map_optical of the camera at the current state.
  Eigen::Isometry3d cameraPose() const;

  /// The command applied from now until the next one.
  void applyCommand(const Command& cmd);
  uint32_t commandsReceived() const { return commands_; }

  /// One tick of physics; returns the termination reached, or kNone.
  Termination step();

  double distanceToGoal() const;
  const std::vector<TrajectorySample>& trajectory() const { return trajectory_; }
  /// Per request instance (flattened), 0..1; -1 for instances not placed.
  std::vector<float> obstacleVisibility() const;
  const std::vector<RemovedObstacle>& removed() const { return removed_; }
  const std::vector<PlacedObstacle>& placed() const { return placed_; }
  /// "layout:instance" of the obstacle hit, empty if none.
  std::string collisionWith() const { return collision_with_; }
  const SceneSpec& spec() const { return spec_; }
  const RunnerConfig& config() const { return config_; }

 private:
  Renderer* renderer_;
  RunnerConfig config_;
  SceneSpec spec_;
  std::unique_ptr<PhysicsWorld> world_;
  std::vector<PlacedObstacle> placed_;
  std::vector<RemovedObstacle> removed_;
  std::vector<uint32_t> max_pixels_;  // by obstacle id
  std::vector<TrajectorySample> trajectory_;
  VehicleState state_;
  Command command_;
  uint64_t tick_ = 0;
  uint32_t commands_ = 0;
  uint64_t idle_ticks_ = 0, stuck_ticks_ = 0;
  double ground_speed_ = 0.0;
  std::string collision_with_;
  std::vector<uint32_t> histogram_;
};

}  // namespace asg_sim
