#pragma once
// A stack node's side of the lockstep protocol (the planner's; asg_lockstep.StackProtocol is the
// Python twin the segmenter uses), without ROS: which run is current, whether a message belongs
// to it, and whether this node has failed it. Unit-tested in test/test_worker_protocol.cpp.

#include <cstdint>

#include "asg_lockstep/worker_protocol.hpp"

namespace asg_lockstep {

/// [-] announcements (one each 0.5 s) a node may let pass unacknowledged while one of its inputs
/// has no publisher yet (StackProtocol::acknowledge); asg_lockstep.stack_protocol.ACK_DEFERRALS is
/// the Python twin's (test_stack_protocol.py checks they agree).
constexpr int kAckDeferrals = 6;

class StackProtocol {
 public:
  explicit StackProtocol(Nanos window) : window_(window) {}

  /// The worker announced a run (it repeats the announcement until every node has acknowledged).
  /// True when it is a new one: the node then resets for it, and forgets its failure.
  bool announce(uint32_t scenario_id, uint32_t run, Nanos base) {
    if (have_run_ && run == run_) return false;
    have_run_ = true;
    scenario_id_ = scenario_id;
    run_ = run;
    base_ = base;
    failed_ = false;
    stale_ = 0;
    return true;
  }
  /// A message stamped `stamp` belongs to the current run; one that does not is counted as stale.
  bool current(Nanos stamp) {
    if (have_run_ && stamp >= base_ && stamp < base_ + window_) return true;
    ++stale_;
    return false;
  }
  /// A control tick of the current run (of its scenario and in its window).
  bool tick(uint32_t scenario_id, Nanos stamp) { return scenario_id == scenario_id_ && current(stamp); }
  /// Whether to acknowledge the announcement now. A node that has just (re)started subscribes
  /// and advertises before the TCP links exist, and a message sent before then is lost (the run
  /// would end on the command timeout): it defers while `inputs_connected` is false, for at most
  /// kAckDeferrals announcements (~3 s); then it acknowledges and never waits again, so that a
  /// stack lacking an input still runs. gaveUp() says when that happened.
  bool acknowledge(bool inputs_connected) {
    if (gave_up_ || inputs_connected) {
      deferred_ = 0;
      return true;
    }
    if (++deferred_ <= kAckDeferrals) return false;
    gave_up_ = true;
    return true;
  }
  bool gaveUp() const { return gave_up_; }
  /// This node cannot go on with the current run.
  void fail() { failed_ = true; }
  bool failed() const { return failed_; }
  /// A run to work on: announced, and not failed.
  bool active() const { return have_run_ && scenario_id_ != 0 && !failed_; }

  uint32_t scenarioId() const { return scenario_id_; }
  uint32_t run() const { return run_; }
  Nanos base() const { return base_; }
  /// Messages dropped as not of the current run, since it began.
  uint32_t staleInRun() const { return stale_; }

 private:
  Nanos window_;
  bool have_run_ = false, failed_ = false, gave_up_ = false;
  int deferred_ = 0;
  uint32_t scenario_id_ = 0, run_ = 0, stale_ = 0;
  Nanos base_ = 0;
};

}  // namespace asg_lockstep
