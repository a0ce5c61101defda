#pragma once
// The scene worker's side of the lockstep protocol (docs/architecture.md), without ROS: which
// message of the stack counts for the current run, whether every stack node has acknowledged it,
// which command answers the awaited control tick, and whom to blame when the stack falls silent.
// The ROS adapter (asg_sim's scene_worker) only translates messages into these calls and waits;
// every ordering that matters (late, duplicated, out-of-window, missing) is decided here and
// unit-tested (test/test_worker_protocol.cpp).

#include <cstdint>
#include <set>
#include <string>
#include <vector>

namespace asg_lockstep {

using Nanos = int64_t;  ///< [ns] a message stamp

/// The stamps of one run: [base, base + length). Runs get disjoint windows, so a message of an
/// earlier run of the same scenario is recognised by its stamp.
struct RunWindow {
  Nanos base = 0;
  Nanos length = 0;
  bool contains(Nanos t) const { return length > 0 && t >= base && t < base + length; }
};

class WorkerProtocol {
 public:
  struct Config {
    std::vector<std::string> stack_nodes;  ///< nodes that must acknowledge each run
    std::string labels_node;               ///< the node publishing labels ("": none is watched)
    bool lockstep = true;                  ///< false: any in-window command counts (free-running)
  };
  explicit WorkerProtocol(Config config);

  /// A run of scenario `scenario_id` (> 0) begins: everything of earlier runs is forgotten.
  void begin(uint32_t scenario_id, uint32_t run, RunWindow window);
  /// No run (between goals): every message is dropped.
  void end();
  bool running() const { return scenario_id_ != 0; }

  /// A stack node's acknowledgement; true when it is of this run (duplicates count once).
  bool ack(uint32_t scenario_id, uint32_t run, const std::string& node);
  /// A stack node's error report; true when it is this run's first.
  bool stackError(uint32_t scenario_id, uint32_t run, const std::string& node, const std::string& reason);
  /// Every stack node has acknowledged this run.
  bool acknowledged() const;
  /// The stack nodes that have not acknowledged this run, comma-separated ("" when none).
  std::string missingAcks() const;
  /// "node: reason" of this run's first stack error ("" when none).
  const std::string& error() const { return error_; }

  /// The worker published a camera frame at `stamp`.
  void cameraFrame(Nanos stamp);
  /// A labels frame of the labels node; true when it is of this run.
  bool labels(Nanos stamp);
  /// The worker published the control tick `stamp` and now waits for its command.
  void await(Nanos stamp);
  /// A vehicle command; true when it answers this run's awaited tick (lockstep) or falls in the
  /// run's window (free-running). The adapter keeps the message when it counts.
  bool command(uint32_t scenario_id, Nanos stamp);
  /// A command answering the awaited tick has arrived (lockstep), or any (free-running).
  bool answered() const { return answered_; }
  /// The adapter applied the command: the next one must answer the next tick.
  void consume() { answered_ = false; }

  /// Who is silent when the command for tick `stamp` does not come: the labels node when the
  /// newest camera frame is still unlabelled, else the first other stack node (the planner).
  std::string blame(Nanos tick_stamp) const;

  uint32_t cameraFrames() const { return camera_frames_; }
  Nanos lastCameraStamp() const { return last_camera_; }
  const RunWindow& window() const { return window_; }

 private:
  Config config_;
  uint32_t scenario_id_ = 0, run_ = 0;
  RunWindow window_;
  std::set<std::string> acks_;
  std::string error_;
  uint32_t camera_frames_ = 0;
  Nanos last_camera_ = 0, last_labels_ = 0, awaited_ = -1, answered_stamp_ = -1;
  bool answered_ = false;
};

}  // namespace asg_lockstep
