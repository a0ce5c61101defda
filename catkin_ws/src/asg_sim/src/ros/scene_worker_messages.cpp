#include "scene_worker_messages.hpp"

#include <sensor_msgs/point_cloud2_iterator.h>

#include <cstdio>

namespace asg_sim {

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

nav_msgs::Odometry odometry(const VehicleState& s, const ros::Time& stamp) {
  nav_msgs::Odometry odom;
  odom.header.stamp = stamp;
  odom.header.frame_id = kOdomFrame;
  odom.child_frame_id = kBaseFrame;
  toPose(s, &odom.pose.pose);
  toTwist(s, &odom.twist.twist);
  return odom;
}

tf2_msgs::TFMessage transforms(const VehicleState& s, const ros::Time& stamp) {
  tf2_msgs::TFMessage tf;
  tf.transforms.push_back(toTransform(s.pose(), stamp, kOdomFrame, kBaseFrame));
  return tf;
}

tf2_msgs::TFMessage staticTransforms(const Eigen::Vector3d& m, bool map_odom) {
  tf2_msgs::TFMessage tf;
  const ros::Time zero;  // static: valid at every time
  if (map_odom) tf.transforms.push_back(toTransform(Eigen::Isometry3d::Identity(), zero, kMapFrame, kOdomFrame));
  // The optical frame straight from base_link (the numbers the planner projects with, unchanged),
  // and the camera's body frame (x forward, z up) beside it for stacks that want one.
  tf.transforms.push_back(toTransform(cameraMount(m.x(), m.y(), m.z()), zero, kBaseFrame, kCameraOpticalFrame));
  tf.transforms.push_back(
      toTransform(Eigen::Isometry3d(Eigen::Translation3d(m)), zero, kBaseFrame, kCameraBodyFrame));
  return tf;
}

sensor_msgs::CameraInfo cameraInfo(const CameraModel& c, const std_msgs::Header& header, int w, int h) {
  sensor_msgs::CameraInfo info;
  info.header = header;
  info.width = w;
  info.height = h;
  info.distortion_model = "plumb_bob";
  info.D.assign(5, 0.0);
  info.K = {c.fx(), 0, c.cx(), 0, c.fy(), c.cy(), 0, 0, 1};
  info.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  info.P = {c.fx(), 0, c.cx(), 0, 0, c.fy(), c.cy(), 0, 0, 0, 1, 0};
  return info;
}

sensor_msgs::PointCloud2 pointCloud(const std::vector<Eigen::Vector3f>& pts, const ros::Time& stamp) {
  sensor_msgs::PointCloud2 cloud;
  cloud.header.stamp = stamp;
  cloud.header.frame_id = kCameraOpticalFrame;
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
  return cloud;
}

asg_msgs::ScenarioInfo announcement(const asg_msgs::RunScenarioGoal& goal, uint32_t run, const ros::Time& base,
                                    int width, int height) {
  const auto& op = goal.scene.operational;
  asg_msgs::ScenarioInfo info;
  info.scenario_id = goal.scenario_id;
  info.run = run;
  info.base_stamp = base;
  info.camera_width = uint32_t(width);
  info.camera_height = uint32_t(height);
  info.landscape_size = goal.scene.structural.landscape.size;
  info.goal_x = op.goal_x;
  info.goal_y = op.goal_y;
  info.goal_radius = op.goal_radius;
  info.speed = op.speed;
  info.start_x = op.start_x;
  info.start_y = op.start_y;
  info.start_yaw = op.start_yaw;
  return info;
}

geometry_msgs::PoseStamped goalPose(const asg_msgs::ScenarioInfo& info) {
  geometry_msgs::PoseStamped goal;
  goal.header.stamp = info.base_stamp;
  goal.header.frame_id = "map";
  goal.pose.position.x = info.goal_x;
  goal.pose.position.y = info.goal_y;
  goal.pose.orientation.w = 1.0;
  return goal;
}

void fillResult(const ScenarioRunner& runner, asg_msgs::RunScenarioResult* result) {
  result->sim_time = runner.time();
  result->num_control_msgs = runner.commandsReceived();
  result->trajectory.reserve(runner.trajectory().size());
  for (const auto& s : runner.trajectory()) {
    asg_msgs::TrajectorySample ts;
    ts.t = s.t;
    toPose(s.state, &ts.pose);
    toTwist(s.state, &ts.twist);
    result->trajectory.push_back(ts);
  }
  result->obstacle_visibility = runner.obstacleVisibility();
  for (const auto& r : runner.removed()) {
    asg_msgs::RemovedObstacle ro;
    ro.layout_index = r.layout_index;
    ro.instance_index = r.instance_index;
    ro.reason = r.reason;
    result->removed_obstacles.push_back(ro);
  }
  result->collision_with = runner.collisionWith();
}

std::string formatSeconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.1f s", s);
  return buf;
}

}  // namespace asg_sim
