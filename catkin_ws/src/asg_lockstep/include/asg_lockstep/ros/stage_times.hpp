// ROS layer (the one ROS header of asg_lockstep, header-only, for the nodes' adapters; the
// library itself uses no ROS): publishes a StageClock as asg_msgs/StageTimes on `stage_times` (latched), at most
// once a second and only when something changed (used by the scene worker and the planner).
#pragma once

#include <asg_msgs/StageTimes.h>
#include <ros/ros.h>

#include <atomic>
#include <string>

#include "asg_lockstep/stage_clock.hpp"

namespace asg_lockstep {

class StageTimesPublisher {
 public:
  StageTimesPublisher(ros::NodeHandle& nh, const std::string& node, const StageClock* clock)
      : node_(node), clock_(clock) {
    pub_ = nh.advertise<asg_msgs::StageTimes>("stage_times", 1, true);
    timer_ = nh.createWallTimer(ros::WallDuration(1.0), [this](const ros::WallTimerEvent&) { publish(false); });
    publish(true);
  }
  void countRun() { ++runs_; }

  void publish(bool always) {
    const auto r = clock_->read();
    double total = 0;
    for (double s : r.seconds) total += s;
    if (!always && total == last_total_ && runs_ == last_runs_) return;
    last_total_ = total;
    last_runs_ = runs_;
    asg_msgs::StageTimes m;
    m.stamp = ros::Time::now();
    m.node = node_;
    m.runs = runs_;
    m.cpu_seconds = r.cpu_seconds;
    m.stages = r.stages;
    m.seconds = r.seconds;
    m.calls.assign(r.calls.begin(), r.calls.end());
    pub_.publish(m);
  }

 private:
  std::string node_;
  const StageClock* clock_;
  ros::Publisher pub_;
  ros::WallTimer timer_;
  std::atomic<uint32_t> runs_{0};
  double last_total_ = -1;
  uint32_t last_runs_ = 0;
};

}  // namespace asg_lockstep
