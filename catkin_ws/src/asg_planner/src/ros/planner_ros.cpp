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

Eigen::Isometry3d toIso(const geometry_msgs::Pose& p) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z)
                   .normalized()
                   .toRotationMatrix();
  T.translation() << p.position.x, p.position.y, p.position.z;
  return T;
}

asg_lockstep::Nanos nanos(const ros::Time& t) { return asg_lockstep::Nanos(t.toNSec()); }

ImageIn image(const sensor_msgs::ImageConstPtr& m) {
  ImageIn i;
  i.encoding = m->encoding;
  i.width = m->width;
  i.height = m->height;
  i.step = m->step;
  i.data = m->data.data();
  i.size = m->data.size();
  i.keep = std::shared_ptr<const void>(m.get(), [m](const void*) {});  // holds the message
  return i;
}

geometry_msgs::Point point(double x, double y, double z = 0.0) {
  geometry_msgs::Point p;
  p.x = x;
  p.y = y;
  p.z = z;
  return p;
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
  if (!sync_.announce(msg->scenario_id, msg->run, asg_lockstep::Nanos(msg->base_stamp.toNSec()))) {
    if (sync_.protocol().failed()) {  // say it again: the first one may have gone out before the worker listened
      error_pub_.publish(last_error_);
      return;
    }
    ack_pub_.publish(ack);
    return;
  }
  auto reset_time = clock_.time(kReset);
  stage_pub_->countRun();
  base_ = msg->base_stamp;
  std::string why;
  if (!gridFits(msg->landscape_size, params_.astar.vehicle_spacing, &why)) {  // bounds A*'s memory
    reportError(why);
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

// Normal after a run ends early (late frames of the last run): counted in PlannerState, not a warning.
void PlannerROS::stale(const ros::Time& stamp, const char* what) {
  ROS_DEBUG_THROTTLE(5.0, "planner: %s stamped %.3f s is not of the current run (window from %.0f s): dropped",
                     what, stamp.toSec(), base_.toSec());
}

void PlannerROS::reportError(const std::string& reason) {
  sync_.protocol().fail();
  asg_msgs::StackError e;
  e.node = ack_name_;
  e.scenario_id = sync_.protocol().scenarioId();
  e.run = sync_.protocol().run();
  e.reason = reason;
  last_error_ = e;
  error_pub_.publish(e);
  ROS_ERROR("planner: scenario %u: %s", sync_.protocol().scenarioId(), reason.c_str());
}

void PlannerROS::onDepth(const sensor_msgs::ImageConstPtr& msg) {
  if (!sync_.addDepth(nanos(msg->header.stamp), image(msg))) return stale(msg->header.stamp, "depth");
  process();
}
void PlannerROS::onLabels(const sensor_msgs::ImageConstPtr& msg) {
  if (!sync_.addLabels(nanos(msg->header.stamp), image(msg))) return stale(msg->header.stamp, "labels");
  process();
}
void PlannerROS::onOdom(const nav_msgs::OdometryConstPtr& msg) {
  OdomIn o;
  o.pose = toIso(msg->pose.pose);
  o.state.x = msg->pose.pose.position.x;
  o.state.y = msg->pose.pose.position.y;
  const auto& q = msg->pose.pose.orientation;
  o.state.yaw = std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
  o.state.speed = msg->twist.twist.linear.x;
  if (!sync_.addOdom(nanos(msg->header.stamp), o)) return stale(msg->header.stamp, "odometry");
  process();
}
void PlannerROS::onTick(const asg_msgs::TickConstPtr& msg) {
  if (!sync_.addTick(msg->scenario_id, nanos(msg->header.stamp), msg->camera_frames)) return;
  process();
}

void PlannerROS::onInfo(const sensor_msgs::CameraInfoConstPtr& msg) {
  K_ = {msg->K[0], msg->K[4], msg->K[2], msg->K[5]};
  sync_.setIntrinsicsKnown(msg->K[0] > 0 && msg->K[4] > 0);
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
    sync_.setMount(toIso(p));
  }
  process();
}

// The frame synchroniser decides what is complete; this only calls the planner and publishes.
void PlannerROS::process() {
  std::string error;
  while (auto f = sync_.nextFrame(&error)) {
    auto votes_time = clock_.time(kVotes);
    planner_->addFrame(f->t, reinterpret_cast<const float*>(f->depth.data), f->labels.data, int(f->depth.width),
                       int(f->depth.height), K_, f->T_map_optical);
  }
  if (!error.empty()) return reportError(error);
  while (auto tick = sync_.nextTick()) {
    const ros::Time stamp = ros::Time().fromNSec(uint64_t(tick->stamp));
    const VehicleState2D& s = tick->state;
    const double t = tick->t;
    bool replanned = false;
    ControlCommand c;
    {
      auto plan_time = clock_.time(kPlan);
      c = planner_->tick(t, s, &replanned);
    }
    auto publish_time = clock_.time(kPublish);
    asg_msgs::VehicleCommand cmd;
    cmd.header.stamp = stamp;
    cmd.scenario_id = sync_.protocol().scenarioId();
    cmd.throttle = c.throttle;
    cmd.steering = c.steering;
    cmd.brake = c.brake;
    cmd.target_speed = c.target_speed;
    cmd_pub_.publish(cmd);

    asg_msgs::PlannerState st;
    st.header.stamp = stamp;
    st.header.frame_id = "map";
    st.scenario_id = sync_.protocol().scenarioId();
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
    st.stale_dropped = sync_.protocol().staleInRun();
    state_pub_.publish(st);
    if (publish_markers_) {
      geometry_msgs::PointStamped lp;
      lp.header = st.header;
      lp.point = st.lookahead;
      lookahead_pub_.publish(lp);
      if (replanned) publishViz(stamp);
    }
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
