#include "asg_lockstep/worker_protocol.hpp"

#include <algorithm>
#include <cstdio>
#include <utility>

namespace asg_lockstep {

WorkerProtocol::WorkerProtocol(Config config) : config_(std::move(config)) {}

void WorkerProtocol::begin(uint32_t scenario_id, uint32_t run, RunWindow window) {
  scenario_id_ = scenario_id;
  run_ = run;
  window_ = window;
  acks_.clear();
  error_.clear();
  camera_frames_ = 0;
  last_camera_ = 0;
  last_labels_ = 0;
  awaited_ = -1;
  answered_stamp_ = -1;
  answered_ = false;
}

void WorkerProtocol::end() { scenario_id_ = 0; }

bool WorkerProtocol::ack(uint32_t scenario_id, uint32_t run, const std::string& node) {
  if (!running() || scenario_id != scenario_id_ || run != run_) return false;
  acks_.insert(node);
  return true;
}

bool WorkerProtocol::stackError(uint32_t scenario_id, uint32_t run, const std::string& node,
                                const std::string& reason) {
  if (!running() || scenario_id != scenario_id_ || run != run_ || !error_.empty()) return false;
  error_ = node + ": " + reason;
  return true;
}

bool WorkerProtocol::acknowledged() const {
  for (const auto& n : config_.stack_nodes)
    if (!acks_.count(n)) return false;
  return true;
}

std::string WorkerProtocol::missingAcks() const {
  std::string out;
  for (const auto& n : config_.stack_nodes)
    if (!acks_.count(n)) out += (out.empty() ? "" : ", ") + n;
  return out;
}

void WorkerProtocol::cameraFrame(Nanos stamp) {
  ++camera_frames_;
  last_camera_ = stamp;
}

bool WorkerProtocol::labels(Nanos stamp) {
  if (!running() || !window_.contains(stamp)) return false;
  last_labels_ = std::max(last_labels_, stamp);
  return true;
}

void WorkerProtocol::await(Nanos stamp) {
  awaited_ = stamp;
  // A command that already answered this very tick (it cannot come earlier in lockstep) stays.
  if (config_.lockstep && answered_stamp_ != stamp) answered_ = false;
}

bool WorkerProtocol::command(uint32_t scenario_id, Nanos stamp) {
  if (!running() || scenario_id != scenario_id_) return false;  // a late answer of another scenario
  if (!window_.contains(stamp)) return false;                   // of an earlier run of this one
  if (config_.lockstep && stamp != awaited_) return false;      // not the tick awaited
  answered_stamp_ = stamp;
  answered_ = true;
  return true;
}

std::string WorkerProtocol::blame(Nanos tick_stamp) const {
  char buf[200];
  if (!config_.labels_node.empty() && camera_frames_ > 0 && last_labels_ < last_camera_) {
    std::snprintf(buf, sizeof(buf), "%s: no labels for the camera frame at t = %.3f s", config_.labels_node.c_str(),
                  double(last_camera_ - window_.base) * 1e-9);
    return buf;
  }
  std::snprintf(buf, sizeof(buf), ": no command for control tick t = %.3f s", double(tick_stamp - window_.base) * 1e-9);
  for (const auto& n : config_.stack_nodes)
    if (n != config_.labels_node) return n + buf;
  return "stack" + std::string(buf);
}

}  // namespace asg_lockstep
