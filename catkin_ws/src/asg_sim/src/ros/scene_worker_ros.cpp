#include "scene_worker_ros.hpp"

#include <asg_msgs/ScenarioInfo.h>
#include <asg_msgs/Tick.h>
#include <asg_msgs/WorkerStatus.h>
#include <geometry_msgs/PoseStamped.h>
#include <nav_msgs/Odometry.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <tf2_msgs/TFMessage.h>

#include <algorithm>
#include <chrono>
#include <thread>
#include <cstdlib>
#include <cstring>

namespace asg_sim {
namespace {

SceneSpec toSpec(const asg_msgs::SceneDescription& m) {
  SceneSpec s;
  s.landscape.size = m.structural.landscape.size;
  s.landscape.subdivisions = m.structural.landscape.subdivisions;
  s.landscape.border = m.structural.landscape.border;
  const auto& t = m.structural.terrain;
  s.terrain.amplitude_m = t.amplitude_m;
  s.terrain.wavelength_m = t.wavelength_m;
  s.terrain.seed = t.seed;
  for (const auto& h : t.hills) s.terrain.hills.push_back({h.x, h.y, h.radius_m, h.height_m});
  for (const auto& l : m.structural.layouts) {
    ObstacleLayout layout;
    layout.mesh_name = l.mesh_name;
    for (const auto& i : l.instances)
      layout.instances.push_back({bool(i.visible), bool(i.cast_shadow), i.x, i.y, i.yaw, i.scale});
    s.layouts.push_back(layout);
  }
  s.textural.sun_inclination_deg = m.textural.sun_inclination_deg;
  s.textural.sun_yaw_deg = m.textural.sun_yaw_deg;
  s.textural.ground_texture_seed = m.textural.ground_texture_seed;
  s.textural.fog_visibility_m = m.textural.fog_visibility_m;
  s.textural.cloud_cover = m.textural.cloud_cover;
  const auto& o = m.operational;
  auto& d = s.operational;
  d.start_x = o.start_x;
  d.start_y = o.start_y;
  d.start_yaw = o.start_yaw;
  d.goal_x = o.goal_x;
  d.goal_y = o.goal_y;
  d.goal_radius = o.goal_radius;
  d.safety_radius = o.safety_radius;
  d.speed = o.speed;
  d.sim_timeout = o.sim_timeout;
  d.idle_timeout = o.idle_timeout;
  d.stuck_timeout = o.stuck_timeout;
  d.max_roll_deg = o.max_roll_deg;
  d.max_pitch_deg = o.max_pitch_deg;
  d.allow_collisions = o.allow_collisions;
  return s;
}

void toPose(const VehicleState& s, geometry_msgs::Pose* p) {
  p->position.x = s.position.x();
  p->position.y = s.position.y();
  p->position.z = s.position.z();
  p->orientation.x = s.orientation.x();
  p->orientation.y = s.orientation.y();
  p->orientation.z = s.orientation.z();
  p->orientation.w = s.orientation.w();
}

void toTwist(const VehicleState& s, geometry_msgs::Twist* t) {
  t->linear.x = s.linear.x();
  t->linear.y = s.linear.y();
  t->linear.z = s.linear.z();
  t->angular.x = s.angular.x();
  t->angular.y = s.angular.y();
  t->angular.z = s.angular.z();
}

geometry_msgs::TransformStamped toTransform(const Eigen::Isometry3d& T, const ros::Time& stamp,
                                            const std::string& parent, const std::string& child) {
  geometry_msgs::TransformStamped t;
  t.header.stamp = stamp;
  t.header.frame_id = parent;
  t.child_frame_id = child;
  const Eigen::Quaterniond q(T.rotation());
  t.transform.translation.x = T.translation().x();
  t.transform.translation.y = T.translation().y();
  t.transform.translation.z = T.translation().z();
  t.transform.rotation.x = q.x();
  t.transform.rotation.y = q.y();
  t.transform.rotation.z = q.z();
  t.transform.rotation.w = q.w();
  return t;
}

template <class T>
void fillImage(sensor_msgs::Image* msg, const ros::Time& stamp, const std::string& encoding,
               int w, int h, int bytes_per_px, const std::vector<T>& data) {
  msg->header.stamp = stamp;
  msg->header.frame_id = "camera";
  msg->width = w;
  msg->height = h;
  msg->encoding = encoding;
  msg->is_bigendian = 0;
  msg->step = w * bytes_per_px;
  msg->data.resize(size_t(msg->step) * h);
  std::memcpy(msg->data.data(), data.data(), msg->data.size());
}

std::string formatSeconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.1f s", s);
  return buf;
}

}  // namespace

SceneWorkerROS::SceneWorkerROS(ros::NodeHandle nh, ros::NodeHandle pnh) : nh_(nh), pnh_(pnh) {
  readParameters();
  protocol_ = std::make_unique<asg_lockstep::WorkerProtocol>(
      asg_lockstep::WorkerProtocol::Config{params_.stack_nodes, params_.labels_node, params_.lockstep});
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

  image_pub_ = nh_.advertise<sensor_msgs::Image>("camera/image", 4);
  depth_pub_ = nh_.advertise<sensor_msgs::Image>("camera/depth", 4);
  info_pub_ = nh_.advertise<sensor_msgs::CameraInfo>("camera/camera_info", 4);
  labels_pub_ = nh_.advertise<sensor_msgs::Image>("camera/labels_gt", 4);
  odom_pub_ = nh_.advertise<nav_msgs::Odometry>("odom", 16);
  tf_pub_ = nh_.advertise<tf2_msgs::TFMessage>("tf", 16);
  tick_pub_ = nh_.advertise<asg_msgs::Tick>("tick", 4);
  scenario_pub_ = nh_.advertise<asg_msgs::ScenarioInfo>("scenario", 1, true);
  status_pub_ = nh_.advertise<asg_msgs::WorkerStatus>("status", 1, true);
  goal_pub_ = nh_.advertise<geometry_msgs::PoseStamped>("goal", 1, true);
  if (params_.publish_points) points_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("camera/points", 4);
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
  ROS_INFO("scene_worker ready in %s (stack: %zu node(s), lockstep %s)", nh_.getNamespace().c_str(),
           params_.stack_nodes.size(), params_.lockstep ? "on" : "off");
}

void SceneWorkerROS::readParameters() {
  auto& p = params_;
  if (!pnh_.getParam("stack_nodes", p.stack_nodes))
    throw std::runtime_error("parameter ~stack_nodes (list of node names) is required");
  pnh_.param("ack_timeout", p.ack_timeout, p.ack_timeout);
  pnh_.param("command_timeout", p.command_timeout, p.command_timeout);
  pnh_.param("lockstep", p.lockstep, p.lockstep);
  pnh_.param("realtime_factor", p.realtime_factor, p.realtime_factor);
  pnh_.param("publish_labels", p.publish_labels, p.publish_labels);
  pnh_.param("odom_every_tick", p.odom_every_tick, p.odom_every_tick);
  pnh_.param("render_threads", p.render_threads, p.render_threads);
  pnh_.param("camera/width", p.width, p.width);
  pnh_.param("camera/height", p.height, p.height);
  pnh_.param("camera/fov_deg", p.fov_deg, p.fov_deg);
  pnh_.param("shadow_map_px", p.shadow_map_px, p.shadow_map_px);
  pnh_.param("visibility_full_px", p.visibility_full_px, p.visibility_full_px);
  pnh_.param("labels_node", p.labels_node, p.labels_node);
  pnh_.param("command_interface", p.command_interface, p.command_interface);
  pnh_.param("publish_points", p.publish_points, p.publish_points);
  pnh_.param("points_stride", p.points_stride, p.points_stride);
  auto check = [](bool ok, const std::string& what) {
    if (!ok) throw std::runtime_error("bad parameter " + what);
  };
  check(p.ack_timeout > 0, "~ack_timeout: must be > 0 s");
  check(p.command_timeout > 0, "~command_timeout: must be > 0 s");
  check(p.realtime_factor > 0, "~realtime_factor: must be > 0");
  check(p.render_threads >= 1 && p.render_threads <= 64, "~render_threads: must be 1..64");
  check(p.width >= 16 && p.width <= 4096 && p.height >= 16 && p.height <= 4096,
        "~camera/width, ~camera/height: must be 16..4096 px");
  check(p.fov_deg > 1 && p.fov_deg < 179, "~camera/fov_deg: must be in (1, 179)");
  check(p.shadow_map_px >= 256 && p.shadow_map_px <= 8192, "~shadow_map_px: must be 256..8192");
  check(p.visibility_full_px > 0, "~visibility_full_px: must be > 0");
  check(p.labels_node.empty() ||
            std::find(p.stack_nodes.begin(), p.stack_nodes.end(), p.labels_node) != p.stack_nodes.end(),
        "~labels_node: must be one of ~stack_nodes (or empty)");
  check(p.command_interface == "vehicle_command" || p.command_interface == "twist",
        "~command_interface: must be vehicle_command or twist, not '" + p.command_interface + "'");
  check(p.points_stride >= 1 && p.points_stride <= 64, "~points_stride: must be 1..64 px");
}

void SceneWorkerROS::publishStatus(uint8_t status, uint32_t scenario_id) {
  asg_msgs::WorkerStatus s;
  s.header.stamp = ros::Time::now();  // wall clock: status is about the process, not the scenario
  s.worker = nh_.getNamespace();
  s.status = status;
  s.scenario_id = scenario_id;
  status_pub_.publish(s);
}

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

bool SceneWorkerROS::waitForCommand(uint32_t /*scenario_id*/, const ros::Time& stamp, Command* out,
                                    std::string* why) {
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

void SceneWorkerROS::publishState(const ros::Time& stamp) {
  const VehicleState& s = runner_->state();
  nav_msgs::Odometry odom;
  odom.header.stamp = stamp;
  odom.header.frame_id = "map";
  odom.child_frame_id = "base_link";
  toPose(s, &odom.pose.pose);
  toTwist(s, &odom.twist.twist);
  odom_pub_.publish(odom);
  tf2_msgs::TFMessage tf;
  tf.transforms.push_back(toTransform(s.pose(), stamp, "map", "base_link"));
  const auto& m = runner_->config().camera_mount;
  tf.transforms.push_back(toTransform(cameraMount(m.x(), m.y(), m.z()), stamp, "base_link", "camera"));
  tf_pub_.publish(tf);
}

void SceneWorkerROS::publishCamera(const ros::Time& stamp, bool labels) {
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
  sensor_msgs::CameraInfo info;
  info.header = img.header;
  info.width = w;
  info.height = h;
  info.distortion_model = "plumb_bob";
  info.D.assign(5, 0.0);
  const CameraModel& c = renderer_->camera();
  info.K = {c.fx(), 0, c.cx(), 0, c.fy(), c.cy(), 0, 0, 1};
  info.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  info.P = {c.fx(), 0, c.cx(), 0, 0, c.fy(), c.cy(), 0, 0, 0, 1, 0};
  // Labels first: a stack on ground truth then has them when the image arrives.
  if (labels && params_.publish_labels) {
    sensor_msgs::Image lab;
    fillImage(&lab, stamp, "mono8", w, h, 1, frame_.labels.data);
    labels_pub_.publish(lab);
  }
  info_pub_.publish(info);
  if (params_.publish_points) publishPoints(stamp);
  depth_pub_.publish(depth);
  image_pub_.publish(img);
  std::lock_guard<std::mutex> lock(mutex_);
  protocol_->cameraFrame(nanos(stamp));
}

// The depth image as a cloud in the camera's optical frame (x right, y down, z forward), every
// points_stride-th pixel with a return.
void SceneWorkerROS::publishPoints(const ros::Time& stamp) {
  const std::vector<Eigen::Vector3f> pts = backProject(frame_.depth, renderer_->camera(), params_.points_stride);
  sensor_msgs::PointCloud2 cloud;
  cloud.header.stamp = stamp;
  cloud.header.frame_id = "camera";
  sensor_msgs::PointCloud2Modifier mod(cloud);
  mod.setPointCloud2FieldsByString(1, "xyz");
  mod.resize(pts.size());
  cloud.height = 1;
  cloud.width = uint32_t(pts.size());
  cloud.is_dense = true;
  sensor_msgs::PointCloud2Iterator<float> x(cloud, "x"), y(cloud, "y"), z(cloud, "z");
  for (const auto& p : pts) {
    *x = p.x();
    *y = p.y();
    *z = p.z();
    ++x, ++y, ++z;
  }
  points_pub_.publish(cloud);
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
  const auto& op = goal->scene.operational;
  asg_msgs::ScenarioInfo info;
  info.scenario_id = goal->scenario_id;
  info.run = current_run_;
  info.base_stamp = base_;
  info.camera_width = uint32_t(params_.width);
  info.camera_height = uint32_t(params_.height);
  info.landscape_size = goal->scene.structural.landscape.size;
  info.goal_x = op.goal_x;
  info.goal_y = op.goal_y;
  info.goal_radius = op.goal_radius;
  info.speed = op.speed;
  info.start_x = op.start_x;
  info.start_y = op.start_y;
  info.start_yaw = op.start_yaw;
  announcement_ = info;
  // The goal as a ROS stack expects it (latched, stamped at the run's t = 0), before the
  // announcement: a stack that acknowledges has had the chance to hear it.
  geometry_msgs::PoseStamped goal_pose;
  goal_pose.header.stamp = base_;
  goal_pose.header.frame_id = "map";
  goal_pose.pose.position.x = op.goal_x;
  goal_pose.pose.position.y = op.goal_y;
  goal_pose.pose.orientation.w = 1.0;
  goal_pub_.publish(goal_pose);
  scenario_pub_.publish(info);
  build_time.reset();
  std::string missing;
  bool acked;
  {
    auto t = clock_.time(kAcks);
    acked = waitForAcks(goal->scenario_id, &missing);
  }
  if (!acked)
    return fail(!protocol_->error().empty() ? protocol_->error()
                                      : "stack node(s) did not acknowledge the scenario within " +
                                            formatSeconds(params_.ack_timeout) + ": " + missing);

  Termination term = Termination::kNone;
  std::string error;
  const bool labels = params_.publish_labels;
  const auto start = std::chrono::steady_clock::now();
  while (term == Termination::kNone) {
    const ros::Time now = stamp(runner_->time());
    // The stack reads odometry at the stamps of camera frames and control ticks only; the other
    // ticks' states are in the result's trajectory (odom_every_tick: publish them anyway).
    if (params_.odom_every_tick || runner_->cameraDue() || runner_->controlDue()) {
      auto t = clock_.time(kPublish);
      publishState(now);
    }
    if (runner_->cameraDue()) publishCamera(now, labels);
    if (runner_->controlDue()) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        protocol_->await(nanos(now));
        last_tick_ = now;
      }
      // Ticks go out in both modes: free-running stacks answer them too, the worker just does
      // not wait for the answer and applies the latest command it has.
      asg_msgs::Tick tick;
      tick.header.stamp = now;
      tick.header.frame_id = "map";
      tick.scenario_id = goal->scenario_id;
      tick.tick = runner_->tick() / runner_->config().control_every;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        tick.last_camera_stamp.fromNSec(uint64_t(protocol_->lastCameraStamp()));
        tick.camera_frames = protocol_->cameraFrames();
      }
      {
        auto t = clock_.time(kPublish);
        tick_pub_.publish(tick);
      }
      Command cmd;
      if (params_.lockstep) {
        bool answered;
        {
          auto t = clock_.time(kWait);
          answered = waitForCommand(goal->scenario_id, now, &cmd, &error);
        }
        if (!answered) {
          term = Termination::kError;
          break;
        }
        runner_->applyCommand(cmd);
      } else {
        std::lock_guard<std::mutex> lock(mutex_);
        // A velocity set point holds until the next one: the controller tracks it every tick.
        if (protocol_->answered() || twist()) {
          cmd = takeCommand();
          protocol_->consume();
          runner_->applyCommand(cmd);
        }
      }
    }
    {
      auto t = clock_.time(kPhysics);
      term = runner_->step();
    }
    if (runner_->tick() % runner_->config().tick_hz == 0) {
      asg_msgs::RunScenarioFeedback fb;
      fb.sim_time = runner_->time();
      fb.distance_to_goal = runner_->distanceToGoal();
      server_->publishFeedback(fb);
    }
    if (!params_.lockstep) {  // free-running: hold simulated time to wall time x factor
      const auto due = start + std::chrono::duration<double>(runner_->time() / params_.realtime_factor);
      std::this_thread::sleep_until(due);
      std::lock_guard<std::mutex> lock(mutex_);
      if (server_->isPreemptRequested()) {
        term = Termination::kError;
        error = "preempted";
      } else if (!protocol_->error().empty()) {
        term = Termination::kError;
        error = protocol_->error();
      }
    }
    if (!ros::ok()) {
      term = Termination::kError;
      error = "ROS is shutting down";
    }
  }
  if (term != Termination::kError || error != "preempted")
    publishState(stamp(runner_->time()));

  auto result_time = std::make_unique<asg_lockstep::StageClock::Section>(&clock_, kResult);
  result.sim_time = runner_->time();
  result.num_control_msgs = runner_->commandsReceived();
  result.trajectory.reserve(runner_->trajectory().size());
  for (const auto& s : runner_->trajectory()) {
    asg_msgs::TrajectorySample ts;
    ts.t = s.t;
    toPose(s.state, &ts.pose);
    toTwist(s.state, &ts.twist);
    result.trajectory.push_back(ts);
  }
  result.obstacle_visibility = runner_->obstacleVisibility();
  for (const auto& r : runner_->removed()) {
    asg_msgs::RemovedObstacle ro;
    ro.layout_index = r.layout_index;
    ro.instance_index = r.instance_index;
    ro.reason = r.reason;
    result.removed_obstacles.push_back(ro);
  }
  result.collision_with = runner_->collisionWith();
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
