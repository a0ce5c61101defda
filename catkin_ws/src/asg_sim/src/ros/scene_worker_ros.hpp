#pragma once
// SceneWorkerROS: the thin ROS adapter around asg_sim::ScenarioRunner. Serves the RunScenario
// action, announces each scenario to the autonomy stack and waits for every stack node's ack,
// then runs the simulator core's lockstep run loop (run_loop.hpp) as its stack side: odometry/tf
// and camera frames out when due, and at each control tick a Tick out and the command stamped
// with it in. Message conversions: scene_worker_messages.hpp; parameters: worker_parameters.hpp (the table), scene_worker_params.cpp (reading it).
// Topics, parameters and the protocol: docs/simulator.md.

#include <actionlib/server/simple_action_server.h>
#include <asg_msgs/RunScenarioAction.h>
#include <asg_msgs/ScenarioInfo.h>
#include <asg_msgs/StackAck.h>
#include <asg_msgs/StackError.h>
#include <sensor_msgs/Image.h>
#include <asg_msgs/VehicleCommand.h>
#include <geometry_msgs/Twist.h>
#include <geometry_msgs/TwistStamped.h>
#include <ros/ros.h>

#include <chrono>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "asg_lockstep/worker_protocol.hpp"
#include "asg_sim/renderer.hpp"
#include "asg_lockstep/ros/stage_times.hpp"
#include "asg_sim/run_loop.hpp"
#include "asg_sim/scenario_runner.hpp"
#include "asg_sim/twist_controller.hpp"
#include "worker_parameters.hpp"
#include "asg_lockstep/stage_clock.hpp"

namespace asg_sim {

class SceneWorkerROS : private LoopStack {
 public:
  SceneWorkerROS(ros::NodeHandle nh, ros::NodeHandle pnh);

 private:
  using Params = WorkerParams;  // worker_parameters.hpp: the table
  bool twist() const { return params_.command_interface == "twist"; }
  void readParameters();
  void readRegistration(std::vector<std::string>* errors);
  void execute(const asg_msgs::RunScenarioGoalConstPtr& goal);
  void onCommand(const asg_msgs::VehicleCommandConstPtr& msg);
  void onTwist(const geometry_msgs::TwistConstPtr& msg);
  void onTwistStamped(const geometry_msgs::TwistStampedConstPtr& msg);
  /// The command of this control tick from what the stack sent last (mutex_ held).
  Command takeCommand();
  void onAck(const asg_msgs::StackAckConstPtr& msg);
  void onStackError(const asg_msgs::StackErrorConstPtr& msg);
  void onLabels(const sensor_msgs::ImageConstPtr& msg);
  /// The run's stamp of simulated time t [s].
  ros::Time stamp(double t) const { return base_ + ros::Duration(t); }
  static asg_lockstep::Nanos nanos(const ros::Time& t) { return asg_lockstep::Nanos(t.toNSec()); }
  void publishStatus(uint8_t status, uint32_t scenario_id);
  void publishState(const ros::Time& stamp);
  void publishCamera(const ros::Time& stamp);
  void publishStatic();
  bool waitForAcks(uint32_t scenario_id, std::string* missing);
  // A stack without acknowledgements (stack/acks false): every one of its nodes is registered
  // with the master; false, naming the missing ones, after ~ack_timeout.
  bool waitForNodes(std::string* missing);
  // Lockstep: waits for the command answering `stamp`; false on timeout or preemption.
  bool waitForCommand(const ros::Time& stamp, Command* out, std::string* why);
  // Each stack node's XML-RPC URI as the master gives it when the run starts, and, on a command
  // timeout, the first node (the labels node first) that has since died or restarted: its URI
  // changed or no longer answers ("" when every one is the same process, still answering).
  void recordNodeUris();
  std::string goneNode();
  std::vector<std::pair<std::string, std::string>> node_uris_;  // (node, URI) of the current run
  // The run loop's stack side (LoopStack).
  bool stateEveryTick() const override { return params_.odom_every_tick; }
  void onState(double t) override;
  void onCamera(double t) override;
  bool onControl(double t, Command* cmd, bool* apply, std::string* error) override;
  void beforeStep() override;
  bool afterStep(std::string* error) override;
  void finish(asg_msgs::RunScenarioResult* result, Termination t, const std::string& error);

  ros::NodeHandle nh_, pnh_;
  Params params_;
  std::unique_ptr<Renderer> renderer_;
  std::unique_ptr<ScenarioRunner> runner_;
  ros::Publisher image_pub_, depth_pub_, info_pub_, depth_info_pub_, labels_pub_, odom_pub_, tf_pub_,
      tf_static_pub_, clock_pub_, tick_pub_, scenario_pub_, status_pub_, points_pub_, goal_pub_;
  ros::Subscriber cmd_sub_, cmd_vel_sub_, ack_sub_, error_sub_, labels_sub_;
  std::unique_ptr<actionlib::SimpleActionServer<asg_msgs::RunScenarioAction>> server_;

  std::mutex mutex_;  // guards protocol_ and latest_ (callbacks run on other threads)
  std::condition_variable cv_;
  // What counts for the current run, and whom to blame: the ROS-free protocol core.
  std::unique_ptr<asg_lockstep::WorkerProtocol> protocol_;
  uint32_t current_run_ = 0;  // goals served so far
  asg_msgs::VehicleCommand latest_;  // the command the protocol accepted last
  // command_interface twist: the velocity set point accepted last (a stop until the first), the
  // controller turning it into throttle and steering, and the run and tick it may answer.
  VelocityCommand latest_velocity_;
  std::unique_ptr<TwistController> twist_controller_;
  uint32_t scenario_id_ = 0;
  ros::Time last_tick_;
  CameraFrame frame_;
  asg_msgs::ScenarioInfo announcement_;
  ros::Time base_;  // stamp of simulated time 0 in the current run
  // Where the worker's time goes (docs/benchmarks.md); the stage order is StageTimes' order.
  enum Stage { kBuild, kAcks, kRender, kPublish, kWait, kPhysics, kResult };
  asg_lockstep::StageClock clock_{{"build", "acks", "render", "publish", "wait", "physics", "result"}};
  std::unique_ptr<asg_lockstep::StageTimesPublisher> stage_pub_;
  std::unique_ptr<asg_lockstep::StageClock::Section> physics_time_;  // open during a physics tick
  std::chrono::steady_clock::time_point run_start_;  // free-running: wall time of simulated t = 0
  static constexpr double kBehindWarnS = 0.25;  // [s, wall] free-running: lag that is reported
};

}  // namespace asg_sim
