#include "planner_ros.hpp"

#include <asg_msgs/PlannerState.h>
#include <asg_msgs/StackAck.h>
#include <asg_msgs/StackError.h>
#include <asg_msgs/VehicleCommand.h>
#include <geometry_msgs/PointStamped.h>
#include <nav_msgs/Path.h>
#include <visualization_msgs/Marker.h>
#include <visualization_msgs/MarkerArray.h>

#include <algorithm>
#include <cmath>

namespace asg_planner {
namespace {

constexpr int kMaxVehicleCellsPerSide = 4096;  // [-] 16.8 M A* nodes at most

Eigen::Isometry3d toIso(const geometry_msgs::Pose& p) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z)
                   .normalized()
                   .toRotationMatrix();
  T.translation() << p.position.x, p.position.y, p.position.z;
  return T;
}

geometry_msgs::Point point(double x, double y, double z = 0.0) {
  geometry_msgs::Point p;
  p.x = x;
  p.y = y;
  p.z = z;
  return p;
}

// Drops entries older than `keep` before `now`.
template <class Map>
void trim(Map* m, const ros::Time& now, double keep) {
  const ros::Time cut = now.toSec() > keep ? now - ros::Duration(keep) : ros::Time();
  while (!m->empty() && m->begin()->first < cut) m->erase(m->begin());
}

}  // namespace

PlannerROS::PlannerROS(ros::NodeHandle nh, ros::NodeHandle pnh) : nh_(nh), pnh_(pnh) {
  readParameters();
  planner_ = std::make_unique<VotingPlanner>(params_);
  cmd_pub_ = nh_.advertise<asg_msgs::VehicleCommand>("cmd", 16);
  ack_pub_ = nh_.advertise<asg_msgs::StackAck>("stack_ack", 4);
  error_pub_ = nh_.advertise<asg_msgs::StackError>("stack_error", 4);
  state_pub_ = nh_.advertise<asg_msgs::PlannerState>("planner/state", 64);
  path_pub_ = nh_.advertise<nav_msgs::Path>("planner/path", 4, true);
  votes_pub_ = nh_.advertise<visualization_msgs::MarkerArray>("planner/votes", 4, true);
  grid_pub_ = nh_.advertise<visualization_msgs::Marker>("planner/vehicle_grid", 1, true);
  lookahead_pub_ = nh_.advertise<geometry_msgs::PointStamped>("planner/lookahead", 16);
  const auto nodelay = ros::TransportHints().tcpNoDelay();
  scenario_sub_ = nh_.subscribe("scenario", 4, &PlannerROS::onScenario, this);
  depth_sub_ = nh_.subscribe("camera/depth", 16, &PlannerROS::onDepth, this, nodelay);
  labels_sub_ = nh_.subscribe("labels", 16, &PlannerROS::onLabels, this, nodelay);
  info_sub_ = nh_.subscribe("camera/camera_info", 4, &PlannerROS::onInfo, this, nodelay);
  odom_sub_ = nh_.subscribe("odom", 64, &PlannerROS::onOdom, this, nodelay);
  tf_sub_ = nh_.subscribe("tf", 16, &PlannerROS::onTf, this, nodelay);
  tick_sub_ = nh_.subscribe("tick", 16, &PlannerROS::onTick, this, nodelay);
  stage_pub_ = std::make_unique<asg_lockstep::StageTimesPublisher>(nh_, "planner", &clock_);
  ROS_INFO("planner ready in %s (vote grid %.1f m, vehicle grid %.1f m, labels from %s)",
           nh_.getNamespace().c_str(), params_.vote_spacing, params_.astar.vehicle_spacing,
           labels_sub_.getTopic().c_str());
}

void PlannerROS::readParameters() {
  auto& p = params_;
  auto get = [&](const std::string& name, double& v, double lo, double hi) {
    pnh_.param(name, v, v);
    if (!(v >= lo && v <= hi))
      throw std::runtime_error("parameter ~" + name + " = " + std::to_string(v) + ": must be in [" +
                               std::to_string(lo) + ", " + std::to_string(hi) + "]");
  };
  get("vote_spacing", p.vote_spacing, 0.1, 100.0);
  int max_votes = int(p.max_votes);
  pnh_.param("max_votes", max_votes, max_votes);
  if (max_votes < 1) throw std::runtime_error("parameter ~max_votes: must be >= 1");
  p.max_votes = uint32_t(max_votes);
  get("first_plan_delay", p.first_plan_delay, 0.0, 60.0);
  get("replan_period", p.replan_period, 0.05, 60.0);
  get("astar/vehicle_spacing", p.astar.vehicle_spacing, 0.1, 100.0);
  get("astar/alpha", p.astar.alpha, 0.0, 100.0);
  get("astar/sigma", p.astar.sigma, 0.01, 100.0);
  get("astar/kernel_sigmas", p.astar.kernel_sigmas, 1.0, 10.0);
  pnh_.param("astar/edge_points", p.astar.edge_points, p.astar.edge_points);
  if (p.astar.edge_points != 1 && p.astar.edge_points != 3)
    throw std::runtime_error("parameter ~astar/edge_points = " + std::to_string(p.astar.edge_points) +
                             ": must be 1 (midpoint) or 3 (ends and midpoint)");
  get("projection/max_height", p.projection.max_height, -100.0, 100.0);
  get("projection/max_range", p.projection.max_range, -1.0, 10000.0);
  int stride = p.projection.stride;
  pnh_.param("projection/stride", stride, stride);
  if (stride < 1 || stride > 64) throw std::runtime_error("parameter ~projection/stride: must be 1..64");
  p.projection.stride = stride;
  pnh_.param("projection/height_above_ground", p.projection.height_above_ground, p.projection.height_above_ground);
  get("projection/ground_cell", p.projection.ground_cell, 0.1, 100.0);
  get("follower/lookahead", p.follower.lookahead, 0.1, 100.0);
  pnh_.param("follower/first_crossing", p.follower.first_crossing, p.follower.first_crossing);
  get("follower/kp", p.follower.kp, 0.0, 10000.0);
  get("follower/kd", p.follower.kd, 0.0, 10000.0);
  get("follower/steering_lock", p.follower.steering_lock, 0.01, 1.5);
  get("follower/derivative_tau", p.follower.derivative_tau, 0.0, 10.0);
  get("follower/speed_kp", p.follower.speed_kp, 0.0, 100.0);
  get("follower/speed_ki", p.follower.speed_ki, 0.0, 100.0);
  get("follower/brake_gain", p.follower.brake_gain, 0.0, 100.0);
  pnh_.param<std::string>("ack_name", ack_name_, "planner");
  pnh_.param("publish_markers", publish_markers_, true);
}

void PlannerROS::onScenario(const asg_msgs::ScenarioInfoConstPtr& msg) {
  asg_msgs::StackAck ack;
  ack.node = ack_name_;
  ack.scenario_id = msg->scenario_id;
  ack.run = msg->run;
  // The worker repeats the announcement until every stack node has acked: reset once, ack always.
  if (!protocol_.announce(msg->scenario_id, msg->run, asg_lockstep::Nanos(msg->base_stamp.toNSec()))) {
    if (protocol_.failed()) {  // say it again: the first one may have gone out before the worker listened
      error_pub_.publish(last_error_);
      return;
    }
    ack_pub_.publish(ack);
    return;
  }
  auto reset_time = clock_.time(kReset);
  stage_pub_->countRun();
  base_ = msg->base_stamp;
  depth_.clear();
  labels_.clear();
  odom_.clear();
  ticks_.clear();
  frames_done_ = 0;
  // The vehicle grid bounds A*'s memory: refuse a landscape it cannot hold instead of swapping.
  const double cells = msg->landscape_size / params_.astar.vehicle_spacing;
  if (!(cells <= kMaxVehicleCellsPerSide)) {
    char buf[200];
    std::snprintf(buf, sizeof(buf),
                  "landscape of %.0f m is %.0f vehicle-grid cells per side at %.2f m spacing "
                  "(at most %d)", msg->landscape_size, cells, params_.astar.vehicle_spacing,
                  kMaxVehicleCellsPerSide);
    reportError(buf);
    return;
  }
  Task task;
  task.goal_x = msg->goal_x;
  task.goal_y = msg->goal_y;
  task.goal_radius = msg->goal_radius;
  task.landscape_size = msg->landscape_size;
  task.speed = msg->speed;
  planner_->reset(task);
  if (publish_markers_) {
    // The vehicle grid, once per scenario.
    visualization_msgs::Marker grid;
    grid.header.frame_id = "map";
    grid.ns = "vehicle_grid";
    grid.type = visualization_msgs::Marker::POINTS;
    grid.scale.x = grid.scale.y = 0.3;
    grid.color.r = grid.color.g = grid.color.b = 0.8f;
    grid.color.a = 0.6f;
    grid.pose.orientation.w = 1.0;
    const double s = params_.astar.vehicle_spacing;
    const int n = int(std::floor(task.landscape_size / s + 1e-9));
    if (n <= 400)
      for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n; ++j) grid.points.push_back(point(i * s, j * s));
    grid_pub_.publish(grid);
    publishViz(ros::Time());
  }
  ack_pub_.publish(ack);
}

bool PlannerROS::current(const ros::Time& stamp, const char* what) {
  if (protocol_.current(asg_lockstep::Nanos(stamp.toNSec()))) return true;
  // Normal after a run ends early (late frames of the last run): counted in PlannerState, not a warning.
  ROS_DEBUG_THROTTLE(5.0, "planner: %s stamped %.3f s is not of the current run (window from %.0f s): dropped",
                    what, stamp.toSec(), base_.toSec());
  return false;
}

void PlannerROS::reportError(const std::string& reason) {
  protocol_.fail();
  asg_msgs::StackError e;
  e.node = ack_name_;
  e.scenario_id = protocol_.scenarioId();
  e.run = protocol_.run();
  e.reason = reason;
  last_error_ = e;
  error_pub_.publish(e);
  ROS_ERROR("planner: scenario %u: %s", protocol_.scenarioId(), reason.c_str());
}

void PlannerROS::onDepth(const sensor_msgs::ImageConstPtr& msg) {
  if (!current(msg->header.stamp, "depth")) return;
  depth_[msg->header.stamp] = msg;
  process();
}
void PlannerROS::onLabels(const sensor_msgs::ImageConstPtr& msg) {
  if (!current(msg->header.stamp, "labels")) return;
  labels_[msg->header.stamp] = msg;
  process();
}
void PlannerROS::onOdom(const nav_msgs::OdometryConstPtr& msg) {
  if (!current(msg->header.stamp, "odometry")) return;
  odom_[msg->header.stamp] = msg;
  process();
}
void PlannerROS::onTick(const asg_msgs::TickConstPtr& msg) {
  if (msg->scenario_id != protocol_.scenarioId() || !current(msg->header.stamp, "tick")) return;
  ticks_.push_back(msg);
  process();
}

void PlannerROS::onInfo(const sensor_msgs::CameraInfoConstPtr& msg) {
  K_ = {msg->K[0], msg->K[4], msg->K[2], msg->K[5]};
  have_info_ = msg->K[0] > 0 && msg->K[4] > 0;
  process();
}

void PlannerROS::onTf(const tf2_msgs::TFMessageConstPtr& msg) {
  for (const auto& t : msg->transforms) {
    if (t.header.frame_id != "base_link" || t.child_frame_id != "camera") continue;
    geometry_msgs::Pose p;
    p.position.x = t.transform.translation.x;
    p.position.y = t.transform.translation.y;
    p.position.z = t.transform.translation.z;
    p.orientation = t.transform.rotation;
    T_base_optical_ = toIso(p);
    have_mount_ = true;
  }
  process();
}

bool PlannerROS::frameValid(const sensor_msgs::Image& d, const sensor_msgs::Image& l, std::string* why) const {
  if (d.encoding != "32FC1") *why = "depth encoding '" + d.encoding + "' (expected 32FC1)";
  else if (l.encoding != "mono8" && l.encoding != "8UC1") *why = "labels encoding '" + l.encoding + "' (expected mono8)";
  else if (d.width != l.width || d.height != l.height) *why = "depth and labels differ in size";
  else if (d.step != d.width * 4 || d.data.size() != size_t(d.step) * d.height) *why = "depth step/size inconsistent";
  else if (l.step != l.width || l.data.size() != size_t(l.step) * l.height) *why = "labels step/size inconsistent";
  else return true;
  return false;
}

void PlannerROS::process() {
  if (!protocol_.active()) return;
  // 1. Vote every frame whose depth, labels and odometry (same stamp) are all here.
  while (have_mount_ && have_info_) {
    bool progressed = false;
    for (auto it = depth_.begin(); it != depth_.end(); ++it) {
      const ros::Time stamp = it->first;
      auto lit = labels_.find(stamp);
      auto oit = odom_.find(stamp);
      if (lit == labels_.end() || oit == odom_.end()) continue;
      std::string why;
      if (!frameValid(*it->second, *lit->second, &why)) {
        char buf[64];
        std::snprintf(buf, sizeof(buf), "cannot use the frame at t = %.3f s: ", (stamp - base_).toSec());
        reportError(buf + why);
        return;
      }
      const Eigen::Isometry3d T = toIso(oit->second->pose.pose) * T_base_optical_;
      auto votes_time = clock_.time(kVotes);
      planner_->addFrame((stamp - base_).toSec(), reinterpret_cast<const float*>(it->second->data.data()),
                         lit->second->data.data(), int(it->second->width), int(it->second->height), K_, T);
      ++frames_done_;
      depth_.erase(it);
      labels_.erase(lit);
      progressed = true;
      break;
    }
    if (!progressed) break;
  }
  // 2. Answer ticks in order, each once every frame up to it is voted and its odometry is here.
  while (!ticks_.empty()) {
    const auto& tick = *ticks_.front();
    if (frames_done_ < tick.camera_frames) return;
    auto oit = odom_.find(tick.header.stamp);
    if (oit == odom_.end()) return;
    const auto& o = *oit->second;
    VehicleState2D s;
    s.x = o.pose.pose.position.x;
    s.y = o.pose.pose.position.y;
    const auto& q = o.pose.pose.orientation;
    s.yaw = std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
    s.speed = o.twist.twist.linear.x;
    bool replanned = false;
    const double t = (tick.header.stamp - base_).toSec();
    ControlCommand c;
    {
      auto plan_time = clock_.time(kPlan);
      c = planner_->tick(t, s, &replanned);
    }
    auto publish_time = clock_.time(kPublish);
    asg_msgs::VehicleCommand cmd;
    cmd.header.stamp = tick.header.stamp;
    cmd.scenario_id = protocol_.scenarioId();
    cmd.throttle = c.throttle;
    cmd.steering = c.steering;
    cmd.brake = c.brake;
    cmd.target_speed = c.target_speed;
    cmd_pub_.publish(cmd);

    asg_msgs::PlannerState st;
    st.header.stamp = tick.header.stamp;
    st.header.frame_id = "map";
    st.scenario_id = protocol_.scenarioId();
    st.frames = planner_->frames();
    st.plan_count = planner_->plans();
    st.replanned = replanned;
    st.path_cost = planner_->path().cost;
    st.expansions = planner_->path().expansions;
    // O(1) counters: the control tick must not walk the octree (it runs 10 x per replan).
    st.voted_vertices = planner_->votes().votedCount();
    st.total_votes = planner_->votes().totalVotes();
    if (replanned)
      for (const auto& p : planner_->path().points) st.path.push_back(point(p.x(), p.y()));
    const auto& la = planner_->follower().lookaheadPoint();
    st.lookahead = point(la.x(), la.y(), planner_->ground().heightOr(la.x(), la.y(), 0.0));
    st.heading_error = planner_->follower().headingError();
    st.throttle = c.throttle;
    st.steering = c.steering;
    st.brake = c.brake;
    st.target_speed = c.target_speed;
    st.stale_dropped = protocol_.staleInRun();
    state_pub_.publish(st);
    if (publish_markers_) {
      geometry_msgs::PointStamped lp;
      lp.header = st.header;
      lp.point = st.lookahead;
      lookahead_pub_.publish(lp);
      if (replanned) publishViz(tick.header.stamp);
    }
    ticks_.pop_front();
    trim(&odom_, tick.header.stamp, 1.0);
  }
}

void PlannerROS::publishViz(const ros::Time& stamp) {
  // Drawn on the ground the stack senses (projection/height_above_ground; else at map z 0).
  const GroundMap& ground = planner_->ground();
  nav_msgs::Path path;
  path.header.stamp = stamp;
  path.header.frame_id = "map";
  for (const auto& p : planner_->path().points) {
    geometry_msgs::PoseStamped ps;
    ps.header = path.header;
    ps.pose.position = point(p.x(), p.y(), ground.heightOr(p.x(), p.y(), 0.0) + 0.1);
    ps.pose.orientation.w = 1.0;
    path.poses.push_back(ps);
  }
  path_pub_.publish(path);
  visualization_msgs::MarkerArray arr;
  visualization_msgs::Marker m;
  m.header = path.header;
  m.ns = "votes";
  m.id = 0;
  m.type = visualization_msgs::Marker::CUBE_LIST;
  m.action = visualization_msgs::Marker::ADD;
  m.pose.orientation.w = 1.0;
  const double s = params_.vote_spacing;
  m.scale.x = m.scale.y = 0.6 * s;
  m.scale.z = 0.1;
  for (const auto& [v, n] : planner_->votes().voted()) {
    m.points.push_back(point(v.i * s, v.j * s, ground.heightOr(v.i * s, v.j * s, 0.0) + 0.05));
    std_msgs::ColorRGBA c;
    const float k = float(n) / float(params_.max_votes);  // intensity by votes
    c.r = 1.0f;
    c.g = 1.0f - k;
    c.b = 0.0f;
    c.a = 0.3f + 0.7f * k;
    m.colors.push_back(c);
  }
  if (m.points.empty()) m.action = visualization_msgs::Marker::DELETE;
  arr.markers.push_back(m);
  votes_pub_.publish(arr);
}

}  // namespace asg_planner
