// ROS layer, header-only: the lockstep client for a roscpp stack of standard messages, the C++
// twin of asg_lockstep.ros.LockstepClient (Python; docs/your-stack.md). The stack creates its
// input subscribers and its cmd_vel publisher through it:
//
//   asg_lockstep::LockstepClient lock(nh, "my_stack", [&] { stack.reset(); });
//   lock.subscribe<nav_msgs::Odometry>("odom", [&](const nav_msgs::OdometryConstPtr& m) { ... });
//   auto cmd = lock.advertiseCmdVel("cmd_vel");   // cmd.publish(twist) as with ros::Publisher
//
// Lockstep (`~lockstep`; unset, the stack registration's `stack/mode`, else true: the table both
// clients read, client_params.hpp, decided in client_settings.hpp): the client acknowledges each
// run, holds the inputs in a TickGate (tick_gate.hpp) and at each control tick runs the stack's
// callbacks in stamp order on its own thread, then answers the tick with the stack's last Twist
// as a TwistStamped on `cmd_vel_stamped`. Inputs are received on a second thread of the
// client's, so the tick can wait for them whatever the stack's own spinner does. Free-running:
// plain subscriptions on the stack's node handle; the client still acknowledges runs.
#pragma once

#include <asg_msgs/ScenarioInfo.h>
#include <asg_msgs/StackAck.h>
#include <asg_msgs/StackError.h>
#include <asg_msgs/Tick.h>
#include <geometry_msgs/Twist.h>
#include <geometry_msgs/TwistStamped.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>

#include <chrono>
#include <condition_variable>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <stdexcept>
#include <vector>

#include "asg_lockstep/client_settings.hpp"
#include "asg_lockstep/stack_protocol.hpp"
#include "asg_lockstep/tick_gate.hpp"

namespace asg_lockstep {

/// When the worker publishes a standard input type (tick_gate.hpp); others need the kind named.
template <class M>
InputKind defaultInputKind() {
  const std::string type = ros::message_traits::datatype<M>();
  if (type == "geometry_msgs/PoseStamped") return InputKind::kRun;
  if (type == "nav_msgs/Odometry") return InputKind::kState;
  if (type == "sensor_msgs/Image" || type == "sensor_msgs/CameraInfo" || type == "sensor_msgs/PointCloud2")
    return InputKind::kCamera;
  throw std::invalid_argument("lockstep input of type " + type +
                              ": the gate does not know when the worker publishes it; pass an InputKind");
}

class LockstepClient {
 public:
  /// `node`: the name in the worker's stack_nodes; `on_run`: called at each new run before it is
  /// acknowledged (reset the stack there).
  LockstepClient(ros::NodeHandle nh, const std::string& node, std::function<void()> on_run = {})
      : nh_(nh),
        node_(node),
        on_run_(std::move(on_run)),
        protocol_(Nanos(asg_msgs::ScenarioInfo::RUN_WINDOW) * 1000000000LL),
        gate_(Nanos(asg_msgs::ScenarioInfo::RUN_WINDOW) * 1000000000LL) {
    lockstep_ = readLockstep();
    ack_pub_ = nh_.advertise<asg_msgs::StackAck>("stack_ack", 4);
    error_pub_ = nh_.advertise<asg_msgs::StackError>("stack_error", 4);
    answer_pub_ = nh_.advertise<geometry_msgs::TwistStamped>("cmd_vel_stamped", 4);
    tick_nh_ = nh_;
    input_nh_ = nh_;
    tick_nh_.setCallbackQueue(&tick_queue_);
    input_nh_.setCallbackQueue(&input_queue_);
    scenario_sub_ = input_nh_.subscribe("scenario", 4, &LockstepClient::onScenario, this);
    if (lockstep_)
      tick_sub_ = tick_nh_.subscribe("tick", 4, &LockstepClient::onTick, this, ros::TransportHints().tcpNoDelay());
    tick_spinner_ = std::make_unique<ros::AsyncSpinner>(1, &tick_queue_);
    input_spinner_ = std::make_unique<ros::AsyncSpinner>(1, &input_queue_);
    tick_spinner_->start();
    input_spinner_->start();
  }
  ~LockstepClient() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      closing_ = true;
    }
    cv_.notify_all();
    tick_spinner_->stop();
    input_spinner_->stop();
  }
  LockstepClient(const LockstepClient&) = delete;
  LockstepClient& operator=(const LockstepClient&) = delete;

  bool lockstep() const { return lockstep_; }

  /// A parameter's value as an error writes it: 'text', 1, 0.5 (else its XML-RPC form).
  static std::string shown(XmlRpc::XmlRpcValue& value) {
    std::ostringstream out;
    switch (value.getType()) {
      case XmlRpc::XmlRpcValue::TypeString: out << "'" << static_cast<std::string>(value) << "'"; break;
      case XmlRpc::XmlRpcValue::TypeInt: out << static_cast<int>(value); break;
      case XmlRpc::XmlRpcValue::TypeDouble: out << static_cast<double>(value); break;
      default: out << value.toXml();
    }
    return out.str();
  }

  /// The node's `~lockstep` as client_settings.hpp decides it; std::invalid_argument names a bad value.
  static bool readLockstep() {
    ParameterRead read;
    XmlRpc::XmlRpcValue value;
    if (ros::NodeHandle("~").getParam(client_params::kLockstep.name, value)) {
      if (value.getType() == XmlRpc::XmlRpcValue::TypeBoolean) {
        read.kind = ParameterRead::kBool;
        read.flag = static_cast<bool>(value);
      } else {
        read.kind = ParameterRead::kOther;
        read.shown = shown(value);
      }
    }
    // the registration's stack/mode, of any type: a value that is no string is refused by name
    // (getParam into a string read it as unset, and the client ran in lockstep; issue #80)
    XmlRpc::XmlRpcValue registered;
    if (!ros::NodeHandle().getParam("stack/mode", registered)) return clientLockstep(read, nullptr);
    if (registered.getType() != XmlRpc::XmlRpcValue::TypeString) throw badRegisteredMode(shown(registered));
    const std::string mode = static_cast<std::string>(registered);
    return clientLockstep(read, &mode);
  }

  /// ros::NodeHandle::subscribe's place for an input of the stack (a type with a header).
  template <class M>
  ros::Subscriber subscribe(const std::string& topic, std::function<void(const boost::shared_ptr<const M>&)> cb,
                            InputKind kind = defaultInputKind<M>()) {
    if (!lockstep_) return nh_.subscribe<M>(topic, 16, cb);
    int index;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      index = gate_.add(nh_.resolveName(topic), kind);
    }
    return input_nh_.subscribe<M>(
        topic, 64,
        [this, index, cb](const boost::shared_ptr<const M>& m) {
          std::lock_guard<std::mutex> lock(mutex_);
          if (gate_.offer(index, Nanos(m->header.stamp.toNSec()), [cb, m] { cb(m); })) cv_.notify_all();
        },
        ros::VoidConstPtr(), ros::TransportHints().tcpNoDelay());
  }

  /// The stack's cmd_vel publisher: publishes as usual and remembers the last Twist, which
  /// answers each tick.
  class CmdVel {
   public:
    void publish(const geometry_msgs::Twist& t) {
      pub_.publish(t);
      *latest_ = t;
    }

   private:
    friend class LockstepClient;
    ros::Publisher pub_;
    geometry_msgs::Twist* latest_ = nullptr;
  };
  CmdVel advertiseCmdVel(const std::string& topic = "cmd_vel") {
    CmdVel c;
    c.pub_ = nh_.advertise<geometry_msgs::Twist>(topic, 1);
    c.latest_ = &latest_;
    return c;
  }

  /// For a stack whose control runs on a timer: in lockstep, `fn(t)` [s of simulated time] runs
  /// at every control tick after its inputs, before the answer.
  void onTick(std::function<void(double)> fn) { on_tick_.push_back(std::move(fn)); }

 private:
  void onScenario(const asg_msgs::ScenarioInfoConstPtr& info) {
    bool fresh;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      fresh = protocol_.announce(info->scenario_id, info->run, Nanos(info->base_stamp.toNSec()));
      if (fresh) {
        gate_.begin(Nanos(info->base_stamp.toNSec()));
        latest_ = geometry_msgs::Twist();
      }
    }
    cv_.notify_all();
    if (fresh && on_run_) {
      try {
        on_run_();
      } catch (const std::exception& e) {
        fail(std::string("on_run failed: ") + e.what());
        return;
      }
    }
    asg_msgs::StackAck ack;
    ack.node = node_;
    ack.scenario_id = info->scenario_id;
    ack.run = info->run;
    ack_pub_.publish(ack);
  }

  void onTick(const asg_msgs::TickConstPtr& tick) {
    const Nanos stamp = Nanos(tick->header.stamp.toNSec());
    std::vector<TickGate::Delivery> batch;
    uint32_t run;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      if (!protocol_.active() || !protocol_.tick(tick->scenario_id, stamp)) return;
      run = protocol_.run();
      if (!gate_.tick(stamp, Nanos(tick->last_camera_stamp.toNSec()), tick->camera_frames)) return;
      auto report = std::chrono::steady_clock::now() + std::chrono::seconds(5);
      while (!gate_.missing().empty()) {
        if (closing_ || !ros::ok() || protocol_.run() != run) return;
        cv_.wait_for(lock, std::chrono::milliseconds(50));
        if (std::chrono::steady_clock::now() >= report) {
          std::string what;
          for (const auto& t : gate_.missing()) what += (what.empty() ? "" : ", ") + t;
          ROS_WARN("%s: control tick still waits for %s (is the worker publishing it?)", node_.c_str(), what.c_str());
          report += std::chrono::seconds(5);
        }
      }
      batch = gate_.release();
    }
    try {
      for (auto& d : batch) d();
      const double t = double(stamp - protocol_.base()) * 1e-9;
      for (auto& fn : on_tick_) fn(t);
    } catch (const std::exception& e) {
      fail(e.what());
      return;
    }
    geometry_msgs::TwistStamped answer;
    answer.header.stamp = tick->header.stamp;
    answer.header.frame_id = "base_link";
    answer.twist = latest_;
    answer_pub_.publish(answer);
  }

  void fail(const std::string& reason) {
    asg_msgs::StackError e;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      protocol_.fail();
      e.scenario_id = protocol_.scenarioId();
      e.run = protocol_.run();
    }
    e.node = node_;
    e.reason = reason;
    ROS_ERROR("%s: %s", node_.c_str(), reason.c_str());
    error_pub_.publish(e);
  }

  ros::NodeHandle nh_, tick_nh_, input_nh_;
  std::string node_;
  std::function<void()> on_run_;
  bool lockstep_ = true, closing_ = false;
  std::mutex mutex_;
  std::condition_variable cv_;
  StackProtocol protocol_;
  TickGate gate_;
  geometry_msgs::Twist latest_;
  std::vector<std::function<void(double)>> on_tick_;
  ros::CallbackQueue tick_queue_, input_queue_;
  std::unique_ptr<ros::AsyncSpinner> tick_spinner_, input_spinner_;
  ros::Publisher ack_pub_, error_pub_, answer_pub_;
  ros::Subscriber scenario_sub_, tick_sub_;
};

}  // namespace asg_lockstep
