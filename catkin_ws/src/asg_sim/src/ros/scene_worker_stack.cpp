// The scene worker's side of the lockstep handshake with its stack: the callbacks of what the
// stack sends (commands, velocity set points, acknowledgements, errors, labels) and the waits
// for acknowledgements and for each tick's answer. The protocol core (asg_lockstep) decides what
// counts; these only translate and wait on the condition variable with wall-clock deadlines.
#include <algorithm>
#include <chrono>
#include <thread>

#include <ros/master.h>
#include <ros/names.h>
#include <cstdio>

#include "scene_worker_ros.hpp"

namespace asg_sim {

// The callbacks only translate: the protocol core decides what counts (asg_lockstep).
void SceneWorkerROS::onCommand(const asg_msgs::VehicleCommandConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!protocol_->command(msg->scenario_id, nanos(msg->header.stamp))) return;
  latest_ = *msg;
  cv_.notify_all();
}

// A plain Twist is the latest set point; it answers a tick only when the worker runs free, since
// nothing in it says which tick it was computed for.
void SceneWorkerROS::onTwist(const geometry_msgs::TwistConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (params_.lockstep || !protocol_->command(scenario_id_, nanos(last_tick_))) return;
  latest_velocity_ = {msg->linear.x, msg->angular.z};
  cv_.notify_all();
}

// A stamped Twist answers the tick of its stamp (the lockstep client sends these).
void SceneWorkerROS::onTwistStamped(const geometry_msgs::TwistStampedConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!protocol_->command(scenario_id_, nanos(msg->header.stamp))) return;
  latest_velocity_ = {msg->twist.linear.x, msg->twist.angular.z};
  latest_.header.stamp = msg->header.stamp;
  cv_.notify_all();
}

Command SceneWorkerROS::takeCommand() {
  if (twist()) {
    const double dt = double(runner_->config().control_every) / runner_->config().tick_hz;
    return twist_controller_->update(latest_velocity_, runner_->state().linear.x(), dt);
  }
  Command cmd;
  cmd.throttle = latest_.throttle;
  cmd.steering = latest_.steering;
  cmd.brake = latest_.brake;
  cmd.target_speed = latest_.target_speed;
  return cmd;
}

void SceneWorkerROS::onAck(const asg_msgs::StackAckConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (protocol_->ack(msg->scenario_id, msg->run, msg->node)) cv_.notify_all();
}

void SceneWorkerROS::onStackError(const asg_msgs::StackErrorConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (protocol_->stackError(msg->scenario_id, msg->run, msg->node, msg->reason)) cv_.notify_all();
}

void SceneWorkerROS::onLabels(const sensor_msgs::ImageConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  protocol_->labels(nanos(msg->header.stamp));
}

bool SceneWorkerROS::waitForAcks(uint32_t scenario_id, std::string* missing) {
  std::unique_lock<std::mutex> lock(mutex_);
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                            std::chrono::duration<double>(params_.ack_timeout));
  auto next_announce = std::chrono::steady_clock::now() + std::chrono::milliseconds(500);
  while (!protocol_->acknowledged() && std::chrono::steady_clock::now() < deadline) {
    if (!ros::ok() || server_->isPreemptRequested() || !protocol_->error().empty()) return false;
    cv_.wait_for(lock, std::chrono::milliseconds(50));
    if (std::chrono::steady_clock::now() >= next_announce) {
      // A stack node that came up late, or whose ack went out before our subscription was
      // connected, hears the announcement again; acks are idempotent.
      scenario_pub_.publish(announcement_);
      next_announce += std::chrono::milliseconds(500);
    }
  }
  if (!protocol_->error().empty()) {
    *missing = protocol_->error();
    return false;
  }
  *missing = protocol_->missingAcks();
  (void)scenario_id;
  return missing->empty();
}

bool SceneWorkerROS::waitForNodes(std::string* missing) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(params_.ack_timeout);
  while (true) {
    std::vector<std::string> up;
    ros::master::getNodes(up);
    missing->clear();
    for (const auto& n : params_.stack_nodes) {
      const std::string name = ros::names::append(nh_.getNamespace(), n);
      if (std::find(up.begin(), up.end(), name) == up.end()) *missing += (missing->empty() ? "" : ", ") + name;
    }
    if (missing->empty()) return true;
    if (!ros::ok() || server_->isPreemptRequested() || std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
}

bool SceneWorkerROS::waitForCommand(const ros::Time& stamp, Command* out, std::string* why) {
  std::unique_lock<std::mutex> lock(mutex_);
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(params_.command_timeout);
  while (!(protocol_->answered() && latest_.header.stamp == stamp)) {
    if (!ros::ok()) {
      *why = "ROS is shutting down";
      return false;
    }
    if (server_->isPreemptRequested()) {
      *why = "preempted";
      return false;
    }
    if (!protocol_->error().empty()) {
      *why = protocol_->error();
      return false;
    }
    if (std::chrono::steady_clock::now() >= deadline) {
      char buf[120];
      std::snprintf(buf, sizeof(buf), " within %.1f s (wall clock); has it died or hung?",
                    params_.command_timeout);
      *why = protocol_->blame(nanos(stamp)) + buf;
      return false;
    }
    cv_.wait_for(lock, std::chrono::milliseconds(50));
  }
  *out = takeCommand();
  return true;
}

}  // namespace asg_sim
