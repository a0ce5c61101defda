#include "asg_sim/scenario_runner.hpp"

#include <cmath>

namespace asg_sim {

const char* terminationName(Termination t) {
  const int k = static_cast<int>(t);
  if (t == Termination::kNone) return "NONE";
  return k >= 0 && k < schema::kTerminationCount ? schema::kTerminationNames[k] : "UNKNOWN";
}

ScenarioRunner::ScenarioRunner(Renderer* renderer, const RunnerConfig& config)
    : renderer_(renderer), config_(config) {}

void ScenarioRunner::reset(const SceneSpec& spec) {
  validateScene(spec);
  spec_ = spec;
  placeObstacles(spec_, &placed_, &removed_);
  world_.reset();  // tear the old world down before building the new one
  world_ = std::make_unique<PhysicsWorld>(spec_, placed_, config_.vehicle);
  if (renderer_) renderer_->setScene(spec_, placed_);
  max_pixels_.assign(instanceCount(spec_) + 1, 0);
  tick_ = 0;
  commands_ = 0;
  idle_ticks_ = stuck_ticks_ = 0;
  ground_speed_ = 0.0;
  collision_with_.clear();
  command_ = Command();
  world_->setCommand(command_);
  state_ = world_->state();
  trajectory_.clear();
  trajectory_.push_back({0.0, state_});
}

Eigen::Isometry3d ScenarioRunner::cameraPose() const {
  const auto& m = config_.camera_mount;
  return state_.pose() * cameraMount(m.x(), m.y(), m.z());
}

void ScenarioRunner::renderCamera(bool with_labels, CameraFrame* out) {
  if (!renderer_) throw std::logic_error("ScenarioRunner has no renderer");
  renderer_->renderCamera(cameraPose(), with_labels, out);
  if (!with_labels) return;
  histogram_.assign(max_pixels_.size(), 0);
  for (uint16_t id : out->instances.data)
    if (id > 0 && id < histogram_.size()) ++histogram_[id];
  for (size_t i = 0; i < histogram_.size(); ++i) max_pixels_[i] = std::max(max_pixels_[i], histogram_[i]);
}

void ScenarioRunner::applyCommand(const Command& cmd) {
  command_ = cmd;
  world_->setCommand(cmd);
  ++commands_;
}

double ScenarioRunner::distanceToGoal() const {
  return std::hypot(state_.position.x() - spec_.operational.goal_x,
                    state_.position.y() - spec_.operational.goal_y);
}

Termination ScenarioRunner::step() {
  world_->step(1.0 / config_.tick_hz, config_.physics_substeps);
  ++tick_;
  const Eigen::Vector3d before = state_.position;
  state_ = world_->state();
  // Ground speed from the displacement over the tick: Bullet's velocity after a step still
  // holds the last substep's unresolved forces (a pushing vehicle at a wall reads 0.03 m/s).
  ground_speed_ = (state_.position - before).head<2>().norm() * config_.tick_hz;
  trajectory_.push_back({time(), state_});
  const auto& op = spec_.operational;
  const auto& L = spec_.landscape;

  if (distanceToGoal() <= op.goal_radius) return Termination::kSuccess;
  if (const uint32_t id = world_->contactObstacle()) {
    for (const auto& p : placed_)
      if (p.id == id) collision_with_ = std::to_string(p.layout_index) + ":" + std::to_string(p.instance_index);
    if (!op.allow_collisions) return Termination::kCollision;
  }
  if (std::abs(state_.roll()) * 180.0 / M_PI > op.max_roll_deg ||
      std::abs(state_.pitch()) * 180.0 / M_PI > op.max_pitch_deg)
    return Termination::kFlipped;
  const auto& p = state_.position;
  if (p.x() < -L.border || p.y() < -L.border || p.x() > L.size + L.border || p.y() > L.size + L.border)
    return Termination::kOutOfBounds;
  const bool still = ground_speed_ <= config_.still_speed;
  const bool wants = std::abs(command_.target_speed) > config_.still_speed;
  idle_ticks_ = (still && !wants) ? idle_ticks_ + 1 : 0;
  stuck_ticks_ = (still && wants) ? stuck_ticks_ + 1 : 0;
  const double hz = config_.tick_hz;
  if (op.stuck_timeout >= 0 && stuck_ticks_ / hz >= op.stuck_timeout) return Termination::kStuckTimeout;
  if (op.idle_timeout >= 0 && idle_ticks_ / hz >= op.idle_timeout) return Termination::kIdlingTimeout;
  if (op.sim_timeout >= 0 && time() >= op.sim_timeout) return Termination::kSimTimeout;
  return Termination::kNone;
}

std::vector<float> ScenarioRunner::obstacleVisibility() const {
  std::vector<float> vis(instanceCount(spec_), -1.0f);
  for (const auto& p : placed_)
    vis[p.id - 1] = float(std::min(1.0, max_pixels_[p.id] / config_.visibility_full_px));
  return vis;
}

}  // namespace asg_sim
