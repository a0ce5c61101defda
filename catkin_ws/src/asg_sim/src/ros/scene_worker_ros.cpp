#include "scene_worker_ros.hpp"

#include <asg_msgs/Tick.h>
#include <asg_msgs/WorkerStatus.h>

#include <chrono>
#include <cstdlib>
#include <thread>

#include "asg_sim/run_loop.hpp"
#include "scene_worker_messages.hpp"

namespace asg_sim {

SceneWorkerROS::SceneWorkerROS(ros::NodeHandle nh, ros::NodeHandle pnh) : nh_(nh), pnh_(pnh) {
  readParameters();
  protocol_ = std::make_unique<asg_lockstep::WorkerProtocol>(
      asg_lockstep::WorkerProtocol::Config{params_.stack_acks ? params_.stack_nodes : std::vector<std::string>(),
                                           params_.labels_node, params_.lockstep});
  // Run tokens differ across worker restarts too, so a stack that outlives its worker resets.
  current_run_ = uint32_t(std::chrono::system_clock::now().time_since_epoch().count() / 1000000) << 8;
  // llvmpipe reads LP_NUM_THREADS when the first context is made; an explicit environment wins.
  setenv("LP_NUM_THREADS", std::to_string(params_.render_threads).c_str(), 0);
  CameraModel cam;
  cam.width = params_.width;
  cam.height = params_.height;
  cam.fov_deg = params_.fov_deg;
  RenderOptions ro;
  ro.shadow_map_px = params_.shadow_map_px;
  renderer_ = std::make_unique<Renderer>(cam, ro);
  RunnerConfig rc;
  rc.visibility_full_px = params_.visibility_full_px;
  runner_ = std::make_unique<ScenarioRunner>(renderer_.get(), rc);
  twist_controller_ = std::make_unique<TwistController>(TwistControllerParams::forVehicle(rc.vehicle));

  // image_pipeline's names: the colour camera's image_raw and camera_info, the depth camera's
  // depth/image_raw and depth/camera_info (the same intrinsics), its cloud depth/points.
  image_pub_ = nh_.advertise<sensor_msgs::Image>("camera/image_raw", 4);
  depth_pub_ = nh_.advertise<sensor_msgs::Image>("camera/depth/image_raw", 4);
  info_pub_ = nh_.advertise<sensor_msgs::CameraInfo>("camera/camera_info", 4);
  depth_info_pub_ = nh_.advertise<sensor_msgs::CameraInfo>("camera/depth/camera_info", 4);
  labels_pub_ = nh_.advertise<sensor_msgs::Image>("camera/labels_gt", 4);
  odom_pub_ = nh_.advertise<nav_msgs::Odometry>("odom", 16);
  tf_pub_ = nh_.advertise<tf2_msgs::TFMessage>("tf", 16);
  tf_static_pub_ = nh_.advertise<tf2_msgs::TFMessage>("tf_static", 1, true);
  if (params_.publish_clock) clock_pub_ = nh_.advertise<rosgraph_msgs::Clock>("clock", 16);
  tick_pub_ = nh_.advertise<asg_msgs::Tick>("tick", 4);
  scenario_pub_ = nh_.advertise<asg_msgs::ScenarioInfo>("scenario", 1, true);
  status_pub_ = nh_.advertise<asg_msgs::WorkerStatus>("status", 1, true);
  goal_pub_ = nh_.advertise<geometry_msgs::PoseStamped>("goal", 1, true);
  if (params_.publish_points) points_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("camera/depth/points", 4);
  publishStatic();
  if (twist()) {  // a stack of standard messages; lockstep answers come stamped (docs/your-stack.md)
    cmd_sub_ = nh_.subscribe("cmd_vel", 16, &SceneWorkerROS::onTwist, this, ros::TransportHints().tcpNoDelay());
    cmd_vel_sub_ = nh_.subscribe("cmd_vel_stamped", 16, &SceneWorkerROS::onTwistStamped, this,
                                 ros::TransportHints().tcpNoDelay());
  } else {
    cmd_sub_ = nh_.subscribe("cmd", 16, &SceneWorkerROS::onCommand, this, ros::TransportHints().tcpNoDelay());
  }
  ack_sub_ = nh_.subscribe("stack_ack", 16, &SceneWorkerROS::onAck, this);
  error_sub_ = nh_.subscribe("stack_error", 16, &SceneWorkerROS::onStackError, this);
  if (!params_.labels_node.empty())
    labels_sub_ = nh_.subscribe("labels", 16, &SceneWorkerROS::onLabels, this, ros::TransportHints().tcpNoDelay());
  server_ = std::make_unique<actionlib::SimpleActionServer<asg_msgs::RunScenarioAction>>(
      nh_, "run_scenario", [this](const asg_msgs::RunScenarioGoalConstPtr& g) { execute(g); }, false);
  stage_pub_ = std::make_unique<asg_lockstep::StageTimesPublisher>(nh_, "scene_worker", &clock_);
  server_->start();
  publishStatus(asg_msgs::WorkerStatus::ONLINE_AND_READY, 0);
  ROS_INFO("scene_worker ready in %s (stack %s: %zu node(s), %s, %s)", nh_.getNamespace().c_str(),
           params_.stack_name.empty() ? "unregistered" : params_.stack_name.c_str(), params_.stack_nodes.size(),
           params_.lockstep ? "lockstep" : "free-running", params_.stack_sim_time ? "simulated time" : "wall time");
}

void SceneWorkerROS::publishStatus(uint8_t status, uint32_t scenario_id) {
  asg_msgs::WorkerStatus s;
  s.header.stamp = ros::Time::now();  // wall clock: status is about the process, not the scenario
  s.worker = nh_.getNamespace();
  s.status = status;
  s.scenario_id = scenario_id;
  status_pub_.publish(s);
}

// The transforms that never change (REP 105, tf2's static convention: one latched message).
void SceneWorkerROS::publishStatic() {
  tf_static_pub_.publish(staticTransforms(runner_->config().camera_mount, params_.publish_map_odom));
}

void SceneWorkerROS::publishState(const ros::Time& stamp) {
  // The clock first: a node on simulated time is at `stamp` when the messages stamped so arrive.
  if (params_.publish_clock) {
    rosgraph_msgs::Clock c;
    c.clock = stamp;
    clock_pub_.publish(c);
  }
  odom_pub_.publish(odometry(runner_->state(), stamp));
  tf_pub_.publish(transforms(runner_->state(), stamp));
}

void SceneWorkerROS::publishCamera(const ros::Time& stamp) {
  // The label pass always runs: per-obstacle visibility comes from its instance ids, whatever
  // labels the stack uses; the labels themselves are published only when asked for.
  {
    auto t = clock_.time(kRender);
    runner_->renderCamera(true, &frame_);
  }
  auto publish_time = clock_.time(kPublish);
  const int w = frame_.rgb.width, h = frame_.rgb.height;
  sensor_msgs::Image img, depth;
  fillImage(&img, stamp, "rgb8", w, h, 3, frame_.rgb.data);
  fillImage(&depth, stamp, "32FC1", w, h, 4, frame_.depth.data);
  // Labels first: a stack on ground truth then has them when the image arrives.
  if (params_.publish_labels) {
    sensor_msgs::Image lab;
    fillImage(&lab, stamp, "mono8", w, h, 1, frame_.labels.data);
    labels_pub_.publish(lab);
  }
  info_pub_.publish(cameraInfo(renderer_->camera(), img.header, w, h));
  if (depth_info_pub_.getNumSubscribers() > 0) depth_info_pub_.publish(cameraInfo(renderer_->camera(), img.header, w, h));
  // The depth image as a cloud in the camera's optical frame, every points_stride-th pixel with a return.
  if (params_.publish_points)
    points_pub_.publish(pointCloud(backProject(frame_.depth, renderer_->camera(), params_.points_stride), stamp));
  depth_pub_.publish(depth);
  image_pub_.publish(img);
  std::lock_guard<std::mutex> lock(mutex_);
  protocol_->cameraFrame(nanos(stamp));
}

// The run loop's stack side: what the worker publishes and waits for at each tick.
void SceneWorkerROS::onState(double t) {
  auto publish_time = clock_.time(kPublish);
  publishState(stamp(t));
}

void SceneWorkerROS::onCamera(double t) { publishCamera(stamp(t)); }

bool SceneWorkerROS::onControl(double t, Command* cmd, bool* apply, std::string* error) {
  const ros::Time now = stamp(t);
  asg_msgs::Tick tick;
  tick.header.stamp = now;
  tick.header.frame_id = "map";
  tick.tick = runner_->tick() / runner_->config().control_every;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    protocol_->await(nanos(now));
    last_tick_ = now;
    tick.scenario_id = scenario_id_;
    tick.last_camera_stamp.fromNSec(uint64_t(protocol_->lastCameraStamp()));
    tick.camera_frames = protocol_->cameraFrames();
  }
  // Ticks go out in both modes: free-running stacks answer them too, the worker just does not
  // wait for the answer and applies the latest command it has.
  {
    auto publish_time = clock_.time(kPublish);
    tick_pub_.publish(tick);
  }
  if (params_.lockstep) {
    auto wait_time = clock_.time(kWait);
    return waitForCommand(now, cmd, error);
  }
  std::lock_guard<std::mutex> lock(mutex_);
  // A velocity set point holds until the next one: the controller tracks it every tick.
  *apply = protocol_->answered() || twist();
  if (*apply) {
    *cmd = takeCommand();
    protocol_->consume();
  }
  return true;
}

void SceneWorkerROS::beforeStep() { physics_time_ = std::make_unique<asg_lockstep::StageClock::Section>(&clock_, kPhysics); }

bool SceneWorkerROS::afterStep(std::string* error) {
  physics_time_.reset();
  if (runner_->tick() % runner_->config().tick_hz == 0) {
    asg_msgs::RunScenarioFeedback fb;
    fb.sim_time = runner_->time();
    fb.distance_to_goal = runner_->distanceToGoal();
    server_->publishFeedback(fb);
  }
  bool go_on = true;
  if (!params_.lockstep) {  // free-running: hold simulated time to wall time x factor
    const auto due = run_start_ + std::chrono::duration<double>(runner_->time() / params_.realtime_factor);
    const double behind = std::chrono::duration<double>(std::chrono::steady_clock::now() - due).count();
    if (behind > kBehindWarnS)  // the worker (rendering, physics) cannot hold the factor
      ROS_WARN_THROTTLE(5.0, "scene_worker: free-running at %.2fx, simulated t = %.2f s is %.2f s behind wall time",
                        params_.realtime_factor, runner_->time(), behind);
    std::this_thread::sleep_until(due);
    std::lock_guard<std::mutex> lock(mutex_);
    if (server_->isPreemptRequested()) {
      go_on = false;
      *error = "preempted";
    } else if (!protocol_->error().empty()) {
      go_on = false;
      *error = protocol_->error();
    }
  }
  if (!ros::ok()) {
    go_on = false;
    *error = "ROS is shutting down";
  }
  return go_on;
}

void SceneWorkerROS::finish(asg_msgs::RunScenarioResult* r, Termination t, const std::string& error) {
  r->termination = uint8_t(t);
  r->termination_name = terminationName(t);
  r->error = error;
}

void SceneWorkerROS::execute(const asg_msgs::RunScenarioGoalConstPtr& goal) {
  asg_msgs::RunScenarioResult result;
  result.scenario_id = goal->scenario_id;
  const auto wall0 = std::chrono::steady_clock::now();
  auto fail = [&](const std::string& why) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      protocol_->end();
    }
    publishStatus(asg_msgs::WorkerStatus::ONLINE_AND_READY, 0);
    if (server_->isPreemptRequested()) {  // a cancel before the run started is still a cancel
      finish(&result, Termination::kError, "preempted");
      server_->setPreempted(result, "preempted");
      return;
    }
    ROS_ERROR("scenario %u: %s", goal->scenario_id, why.c_str());
    finish(&result, Termination::kError, why);
    server_->setAborted(result, why);
  };
  if (goal->scenario_id == 0) return fail("scenario_id must be > 0");
  if (goal->top_down_px > 4096) return fail("top_down_px = " + std::to_string(goal->top_down_px) + ": must be <= 4096");
  stage_pub_->countRun();
  auto build_time = std::make_unique<asg_lockstep::StageClock::Section>(&clock_, kBuild);
  try {
    runner_->reset(toSpec(goal->scene));
  } catch (const SceneError& e) {
    return fail(e.what());
  } catch (const std::exception& e) {
    return fail(std::string("could not build the scene: ") + e.what());
  }
  publishStatus(asg_msgs::WorkerStatus::ONLINE_AND_RUNNING, goal->scenario_id);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++current_run_;
    // Disjoint stamp windows per run (ScenarioInfo.RUN_WINDOW); 2^19 windows fit in ros::Time.
    base_ = ros::Time(double(current_run_ % 524287u + 1u) * asg_msgs::ScenarioInfo::RUN_WINDOW);
    protocol_->begin(goal->scenario_id, current_run_,
                     {nanos(base_), nanos(ros::Time(asg_msgs::ScenarioInfo::RUN_WINDOW))});
    scenario_id_ = goal->scenario_id;
    last_tick_ = base_;
    latest_velocity_ = VelocityCommand();
    twist_controller_->reset();
  }
  announcement_ = announcement(*goal, current_run_, base_, params_.width, params_.height);
  // The goal as a ROS stack expects it, before the announcement: a stack that acknowledges has
  // had the chance to hear it.
  goal_pub_.publish(goalPose(announcement_));
  scenario_pub_.publish(announcement_);
  build_time.reset();
  std::string missing;
  bool acked;
  {
    auto t = clock_.time(kAcks);
    acked = params_.stack_acks ? waitForAcks(goal->scenario_id, &missing) : waitForNodes(&missing);
  }
  if (!acked)
    return fail(!protocol_->error().empty() ? protocol_->error()
                : std::string(params_.stack_acks ? "stack node(s) did not acknowledge the scenario within "
                                                 : "stack node(s) not up within ") +
                      formatSeconds(params_.ack_timeout) + ": " + missing);

  if (params_.lockstep) recordNodeUris();  // whom to blame if a node dies mid-run
  // The lockstep run loop of the simulator core; this class is its stack side (below).
  run_start_ = std::chrono::steady_clock::now();
  const LoopEnd end = runLoop(runner_.get(), this);
  const Termination term = end.termination;
  const std::string& error = end.error;
  if (term != Termination::kError || error != "preempted")
    publishState(stamp(runner_->time()));

  auto result_time = std::make_unique<asg_lockstep::StageClock::Section>(&clock_, kResult);
  fillResult(*runner_, &result);
  if (goal->top_down_px > 0) {
    RgbImage top;
    renderer_->renderTopDown(int(goal->top_down_px), &top);
    fillImage(&result.top_down, stamp(runner_->time()), "rgb8", top.width, top.height, 3, top.data);
    result.top_down.header.frame_id = "map";
  }
  result_time.reset();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    protocol_->end();
  }
  publishStatus(asg_msgs::WorkerStatus::ONLINE_AND_READY, 0);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  if (server_->isPreemptRequested()) {
    finish(&result, Termination::kError, "preempted");
    server_->setPreempted(result, "preempted");
    return;
  }
  finish(&result, term, error);
  ROS_INFO("scenario %u: %s after %.2f s simulated (%.2f s wall, %u commands)%s%s", goal->scenario_id,
           terminationName(term), runner_->time(), wall, result.num_control_msgs,
           error.empty() ? "" : ": ", error.c_str());
  if (term == Termination::kError)
    server_->setAborted(result, error);
  else
    server_->setSucceeded(result);
}

}  // namespace asg_sim
