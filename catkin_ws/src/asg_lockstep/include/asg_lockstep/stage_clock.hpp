// Where a process's time goes: wall seconds and calls per named stage, plus the process's CPU
// time, accumulated since it started (no ROS; the nodes publish it as asg_msgs/StageTimes and
// `scripts/repro/bench.sh` turns two readings into a per-scenario breakdown, docs/benchmarks.md).
#pragma once

#include <time.h>

#include <chrono>
#include <mutex>
#include <string>
#include <vector>

namespace asg_lockstep {

class StageClock {
 public:
  // Stages are fixed at construction; index i of every vector below is stage i.
  explicit StageClock(std::vector<std::string> stages)
      : stages_(std::move(stages)), seconds_(stages_.size(), 0.0), calls_(stages_.size(), 0) {}

  // Times one section: `auto t = clock.time(STAGE);` ... end of scope.
  class Section {
   public:
    Section(StageClock* c, size_t stage) : c_(c), stage_(stage), t0_(std::chrono::steady_clock::now()) {}
    ~Section() { c_->add(stage_, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count()); }
    Section(const Section&) = delete;
    Section& operator=(const Section&) = delete;

   private:
    StageClock* c_;
    size_t stage_;
    std::chrono::steady_clock::time_point t0_;
  };
  Section time(size_t stage) { return Section(this, stage); }

  void add(size_t stage, double seconds) {
    std::lock_guard<std::mutex> lock(mutex_);
    seconds_[stage] += seconds;
    ++calls_[stage];
  }

  struct Reading {
    std::vector<std::string> stages;
    std::vector<double> seconds;
    std::vector<uint64_t> calls;
    double cpu_seconds = 0;  // the whole process, all threads
  };
  Reading read() const {
    std::lock_guard<std::mutex> lock(mutex_);
    Reading r{stages_, seconds_, calls_, 0.0};
    timespec ts{};
    if (clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts) == 0) r.cpu_seconds = ts.tv_sec + ts.tv_nsec * 1e-9;
    return r;
  }

 private:
  std::vector<std::string> stages_;
  std::vector<double> seconds_;
  std::vector<uint64_t> calls_;
  mutable std::mutex mutex_;
};

}  // namespace asg_lockstep
