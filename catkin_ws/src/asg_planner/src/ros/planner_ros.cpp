#include "planner_ros.hpp"

#include "asg_lockstep/ros/param_reader.hpp"

#include <stdexcept>

#include "planner_messages.hpp"

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
asg_lockstep::Nanos nanos(const ros::Time& t) { return asg_lockstep::Nanos(t.toNSec()); }
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
  depth_sub_ = nh_.subscribe("camera/depth/image_raw", 16, &PlannerROS::onDepth, this, nodelay);
  labels_sub_ = nh_.subscribe("labels", 16, &PlannerROS::onLabels, this, nodelay);
  info_sub_ = nh_.subscribe("camera/camera_info", 4, &PlannerROS::onInfo, this, nodelay);
  odom_sub_ = nh_.subscribe("odom", 64, &PlannerROS::onOdom, this, nodelay);
  tf_sub_ = nh_.subscribe("tf_static", 4, &PlannerROS::onTf, this, nodelay);  // the camera's mount
  tick_sub_ = nh_.subscribe("tick", 16, &PlannerROS::onTick, this, nodelay);
  stage_pub_ = std::make_unique<asg_lockstep::StageTimesPublisher>(nh_, "planner", &clock_);
  ROS_INFO("planner ready in %s (vote grid %.1f m, vehicle grid %.1f m, labels from %s)",
           nh_.getNamespace().c_str(), params_.vote_spacing, params_.astar.vehicle_spacing,
           labels_sub_.getTopic().c_str());
}

namespace {

namespace params = asg_lockstep::params;

// The ROS adapter's own two parameters, in the same table helper as the core's.
const params::Table<AdapterParams> kAdapterTable = {
    {"ack_name", params::Kind::kText, "-", 0, 0, false, "string, not empty",
     "name used in `stack_ack` (the ROS adapter's)", ASG_PARAM_TEXT(AdapterParams, ack_name)},
    {"publish_markers", params::Kind::kBool, "-", 0, 1, false, "bool", "publish the rviz topics (the ROS adapter's)",
     ASG_PARAM_FLAG(AdapterParams, publish_markers)},
};

}  // namespace

// The planner's table (parameters.hpp) and the adapter's name, type and bound every parameter;
// each is read by its kind (params::readTable): a value of another type is refused by name, as
// one out of range is, where NodeHandle::param would keep the default (a string for follower/kp
// ran with the default gain).
void PlannerROS::readParameters() {
  std::vector<std::string> errors;
  params::readTable(pnh_, "", "~", plannerParameters(), &params_, &errors);
  AdapterParams a;
  params::readTable(pnh_, "", "~", kAdapterTable, &a, &errors);
  if (a.ack_name.empty()) errors.push_back("~ack_name = '': must be a string, not empty");
  if (!errors.empty()) throw std::invalid_argument(params::joinErrors(errors));
  ack_name_ = a.ack_name;
  publish_markers_ = a.publish_markers;
}

std::string plannerNodeParameterTable() {
  return parameterTableMarkdown() + params::markdownRows(kAdapterTable);
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
    if (inputsConnected()) ack_pub_.publish(ack);
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
  if (publish_markers_) {  // the vehicle grid once per scenario, and the empty plan and votes
    grid_pub_.publish(vehicleGridMarker(params_.astar.vehicle_spacing, task.landscape_size));
    publishViz(ros::Time());
  }
  if (inputsConnected()) ack_pub_.publish(ack);  // else the worker announces again in 0.5 s
}

// A planner subscribes before the TCP links to its publishers exist, and a just (re)started
// segmenter acks once *a* listener of its labels is connected, which may be the worker's: labels
// sent before the planner's link is up are lost and the run ends on the command timeout (seen
// once on a slow segmenter start, issue #53). So the planner acks only when every input it steers
// by has a publisher; how long it waits for that is the protocol's rule (StackProtocol::acknowledge).
bool PlannerROS::inputsConnected() {
  const ros::Subscriber* missing = nullptr;
  for (const ros::Subscriber* s : {&depth_sub_, &labels_sub_, &odom_sub_, &tick_sub_})
    if (!missing && s->getNumPublishers() == 0) missing = s;
  const bool had_given_up = sync_.protocol().gaveUp();
  const bool ack = sync_.protocol().acknowledge(missing == nullptr);
  if (missing && ack && !had_given_up)
    ROS_WARN("planner: no publisher on %s after %d announcements: acking anyway from now on",
             missing->getTopic().c_str(), asg_lockstep::kAckDeferrals);
  return ack;
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
  if (!sync_.addDepth(nanos(msg->header.stamp), toImage(msg))) return stale(msg->header.stamp, "depth");
  process();
}
void PlannerROS::onLabels(const sensor_msgs::ImageConstPtr& msg) {
  if (!sync_.addLabels(nanos(msg->header.stamp), toImage(msg))) return stale(msg->header.stamp, "labels");
  process();
}
void PlannerROS::onOdom(const nav_msgs::OdometryConstPtr& msg) {
  const OdomIn o = toOdom(msg->pose.pose, msg->twist.twist.linear.x);
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
    if (t.header.frame_id != "base_link" || t.child_frame_id != "camera_optical") continue;
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

    asg_msgs::PlannerState st = stateMessage(*planner_, c, replanned);
    st.header.stamp = stamp;
    st.scenario_id = sync_.protocol().scenarioId();
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
  path_pub_.publish(pathMessage(*planner_, stamp));
  votes_pub_.publish(voteMarkers(*planner_, stamp));
}

}  // namespace asg_planner
