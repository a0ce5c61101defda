#pragma once
// The input gate of a foreign stack in lockstep, without ROS: the C++ twin of asg_lockstep.gate
// (Python), which documents the rule. Input messages are held back and handed over, tick by tick,
// in (stamp, topic order, arrival) order, once every message the worker published up to the tick
// is here: for a `kRun` topic one of the current run (the goal), for `kState` one stamped at the
// tick (odometry), for `kCamera` one stamped at the tick's last camera frame. Unit-tested in
// test/test_tick_gate.cpp; the ROS client around it is ros/lockstep_client.hpp.

#include <algorithm>
#include <cstdint>
#include <functional>
#include <map>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "asg_lockstep/worker_protocol.hpp"

namespace asg_lockstep {

enum class InputKind { kRun, kState, kCamera };

class TickGate {
 public:
  using Delivery = std::function<void()>;  // hands one held message to the stack's callback

  explicit TickGate(Nanos window) : window_(window) {}

  /// An input topic; returns its index (its place in the delivery order at one stamp).
  int add(const std::string& topic, InputKind kind) {
    topics_.push_back({topic, kind});
    return int(topics_.size()) - 1;
  }
  /// A new run from `base`: what is held of other runs is dropped (counted), what arrived of this
  /// one before its announcement (the goal, published first) is kept.
  void begin(Nanos base) {
    base_ = base;
    have_base_ = true;
    std::vector<Held> keep;
    for (auto& h : held_)
      if (current(h.stamp)) keep.push_back(std::move(h));
    stale_ += held_.size() - keep.size();
    held_ = std::move(keep);
    newest_.clear();
    for (const auto& h : held_) note(h.topic, h.stamp);
    pending_ = false;
  }
  /// A message of input `topic` arrived: held if of this run or a later one; false (and counted)
  /// if of an earlier run.
  bool offer(int topic, Nanos stamp, Delivery deliver) {
    if (topic < 0 || topic >= int(topics_.size())) throw std::out_of_range("TickGate: unknown input topic");
    if (have_base_ && stamp < base_) {
      ++stale_;
      return false;
    }
    held_.push_back({stamp, topic, seq_++, std::move(deliver)});
    if (current(stamp)) note(topic, stamp);
    return true;
  }
  /// The worker waits for the answer to the tick at `stamp`; false for a tick of another run.
  bool tick(Nanos stamp, Nanos last_camera, uint32_t camera_frames) {
    if (!current(stamp)) {
      ++stale_;
      return false;
    }
    pending_ = true;
    tick_ = stamp;
    last_camera_ = last_camera;
    camera_frames_ = camera_frames;
    return true;
  }
  /// The input topics the pending tick still waits for (empty: ready).
  std::vector<std::string> missing() const {
    std::vector<std::string> out;
    if (!pending_) return out;
    for (size_t i = 0; i < topics_.size(); ++i) {
      const auto it = newest_.find(int(i));
      bool ok;
      switch (topics_[i].kind) {
        case InputKind::kRun: ok = it != newest_.end(); break;
        case InputKind::kState: ok = it != newest_.end() && it->second >= tick_; break;
        default: ok = camera_frames_ == 0 || (it != newest_.end() && it->second >= last_camera_);
      }
      if (!ok) out.push_back(topics_[i].name);
    }
    return out;
  }
  /// The held messages of this run stamped up to the pending tick, in delivery order; the rest
  /// stay held.
  std::vector<Delivery> release() {
    std::vector<Delivery> out;
    if (!pending_) return out;
    std::sort(held_.begin(), held_.end(), [](const Held& a, const Held& b) {
      return std::tie(a.stamp, a.topic, a.seq) < std::tie(b.stamp, b.topic, b.seq);
    });
    std::vector<Held> rest;
    for (auto& h : held_) {
      if (current(h.stamp) && h.stamp <= tick_)
        out.push_back(std::move(h.deliver));
      else
        rest.push_back(std::move(h));
    }
    held_ = std::move(rest);
    return out;
  }
  uint64_t stale() const { return stale_; }
  bool pending() const { return pending_; }

 private:
  struct Topic {
    std::string name;
    InputKind kind;
  };
  struct Held {
    Nanos stamp;
    int topic;
    uint64_t seq;
    Delivery deliver;
  };
  bool current(Nanos stamp) const { return have_base_ && stamp >= base_ && stamp < base_ + window_; }
  void note(int topic, Nanos stamp) {
    auto it = newest_.find(topic);
    if (it == newest_.end() || it->second < stamp) newest_[topic] = stamp;
  }

  Nanos window_;
  std::vector<Topic> topics_;
  std::vector<Held> held_;
  std::map<int, Nanos> newest_;
  Nanos base_ = 0, tick_ = 0, last_camera_ = 0;
  uint32_t camera_frames_ = 0;
  uint64_t seq_ = 0, stale_ = 0;
  bool have_base_ = false, pending_ = false;
};

}  // namespace asg_lockstep
