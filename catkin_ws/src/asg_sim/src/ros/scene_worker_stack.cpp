// The scene worker's side of the lockstep handshake with its stack: the callbacks of what the
// stack sends (commands, velocity set points, acknowledgements, errors, labels) and the waits
// for acknowledgements and for each tick's answer. The protocol core (asg_lockstep) decides what
// counts; these only translate and wait on the condition variable with wall-clock deadlines.
#include <algorithm>
#include <chrono>
#include <thread>

#include <ros/master.h>
#include <ros/names.h>
#include <ros/network.h>
#include <fcntl.h>
#include <netdb.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
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
      const std::string blamed = protocol_->blame(nanos(stamp)) + buf;
      // A node that died after its last message reached this worker but not the next node of the
      // stack (a segmenter killed between its two subscribers) would leave the blame on the
      // wrong node: a node that is no longer the process that acknowledged the run is named first.
      lock.unlock();
      const std::string gone = goneNode();
      lock.lock();
      *why = gone.empty() ? blamed : gone + "; " + blamed.substr(blamed.find(':') + 2);
      return false;
    }
    cv_.wait_for(lock, std::chrono::milliseconds(50));
  }
  *out = takeCommand();
  return true;
}

namespace {

// The XML-RPC URI the master holds for `node` ("" when it has none).
std::string lookupNode(const std::string& node) {
  XmlRpc::XmlRpcValue args, result, payload;
  args[0] = ros::this_node::getName();
  args[1] = node;
  if (!ros::master::execute("lookupNode", args, result, payload, false)) return "";
  return payload.getType() == XmlRpc::XmlRpcValue::TypeString ? std::string(payload) : "";
}

// Whether something still listens at the host and port of `uri`: a TCP connection within 0.5 s.
// A process that died leaves its port closed (refused at once); a hung one still accepts, so this
// names only the dead, and cannot itself hang.
bool listening(const std::string& uri) {
  std::string host;
  uint32_t port = 0;
  if (!ros::network::splitURI(uri, host, port)) return true;  // nothing to say: keep the blame
  addrinfo hints{}, *found = nullptr;
  hints.ai_socktype = SOCK_STREAM;
  if (getaddrinfo(host.c_str(), std::to_string(port).c_str(), &hints, &found) != 0 || !found) return true;
  bool open = false;
  const int fd = socket(found->ai_family, found->ai_socktype, found->ai_protocol);
  if (fd >= 0) {
    fcntl(fd, F_SETFL, fcntl(fd, F_GETFL, 0) | O_NONBLOCK);
    int rc = connect(fd, found->ai_addr, found->ai_addrlen);
    if (rc == 0) {
      open = true;
    } else if (errno == EINPROGRESS) {
      pollfd p{fd, POLLOUT, 0};
      int err = 0;
      socklen_t len = sizeof(err);
      open = poll(&p, 1, 500) == 1 && getsockopt(fd, SOL_SOCKET, SO_ERROR, &err, &len) == 0 && err == 0;
    }
    close(fd);
  } else {
    open = true;
  }
  freeaddrinfo(found);
  return open;
}

}  // namespace

void SceneWorkerROS::recordNodeUris() {
  node_uris_.clear();
  std::vector<std::string> order;
  if (!params_.labels_node.empty()) order.push_back(params_.labels_node);
  for (const auto& n : params_.stack_nodes)
    if (n != params_.labels_node) order.push_back(n);
  for (const auto& n : order) {
    const std::string name = ros::names::append(nh_.getNamespace(), n);
    node_uris_.emplace_back(n, lookupNode(name));
  }
}

std::string SceneWorkerROS::goneNode() {
  for (const auto& [node, uri] : node_uris_) {
    if (uri.empty()) continue;  // not known at the start: nothing to compare
    const std::string now = lookupNode(ros::names::append(nh_.getNamespace(), node));
    if (now != uri) return node + ": restarted or gone during the run (the master's URI for it changed)";
    if (!listening(uri)) return node + ": died during the run (nothing listens at its XML-RPC port)";
  }
  return "";
}

}  // namespace asg_sim

