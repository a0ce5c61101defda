#pragma once
// Conversions between the scene worker's messages and the simulator core's types (issue #38:
// out of scene_worker_ros.cpp, which wires them to topics). No decisions here.
#include <asg_msgs/RunScenarioAction.h>
#include <asg_msgs/ScenarioInfo.h>
#include <asg_msgs/SceneDescription.h>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>

#include <cstring>
#include <string>
#include <vector>

#include "asg_sim/renderer.hpp"
#include "asg_sim/scenario_runner.hpp"

namespace asg_sim {

// The frames, by REP 105 and REP 103: map -> odom (identity, static, unless the stack localizes
// itself) -> base_link (the vehicle, x forward, z up) -> camera_optical (x right, y down, z
// forward: images and clouds) and camera_link (the camera's body frame, base_link's axes).
constexpr const char* kMapFrame = "map";
constexpr const char* kOdomFrame = "odom";
constexpr const char* kBaseFrame = "base_link";
constexpr const char* kCameraOpticalFrame = "camera_optical";
constexpr const char* kCameraBodyFrame = "camera_link";

SceneSpec toSpec(const asg_msgs::SceneDescription& m);
void toPose(const VehicleState& s, geometry_msgs::Pose* p);
void toTwist(const VehicleState& s, geometry_msgs::Twist* t);
geometry_msgs::TransformStamped toTransform(const Eigen::Isometry3d& T, const ros::Time& stamp,
                                            const std::string& parent, const std::string& child);

/// Odometry (odom -> base_link, twist in base_link) of a vehicle state.
nav_msgs::Odometry odometry(const VehicleState& s, const ros::Time& stamp);
/// tf: odom -> base_link at `stamp`.
tf2_msgs::TFMessage transforms(const VehicleState& s, const ros::Time& stamp);
/// tf_static: map -> odom (identity, when `map_odom`), base_link -> camera_optical and
/// base_link -> camera_link, for the camera mounted at `camera_mount` [m] in base_link.
tf2_msgs::TFMessage staticTransforms(const Eigen::Vector3d& camera_mount, bool map_odom);
/// The pinhole camera's info (no distortion), with `header`.
sensor_msgs::CameraInfo cameraInfo(const CameraModel& c, const std_msgs::Header& header, int w, int h);
/// Points in the camera's optical frame (x right, y down, z forward) as x y z float32.
sensor_msgs::PointCloud2 pointCloud(const std::vector<Eigen::Vector3f>& pts, const ros::Time& stamp);

template <class T>
void fillImage(sensor_msgs::Image* msg, const ros::Time& stamp, const std::string& encoding, int w, int h,
               int bytes_per_px, const std::vector<T>& data) {
  msg->header.stamp = stamp;
  msg->header.frame_id = kCameraOpticalFrame;
  msg->width = w;
  msg->height = h;
  msg->encoding = encoding;
  msg->is_bigendian = 0;
  msg->step = w * bytes_per_px;
  msg->data.resize(size_t(msg->step) * h);
  std::memcpy(msg->data.data(), data.data(), msg->data.size());
}

/// The announcement of a run (ScenarioInfo) and the goal as a ROS stack expects it (latched,
/// stamped at the run's t = 0).
asg_msgs::ScenarioInfo announcement(const asg_msgs::RunScenarioGoal& goal, uint32_t run, const ros::Time& base,
                                    int width, int height);
geometry_msgs::PoseStamped goalPose(const asg_msgs::ScenarioInfo& info);

/// The run's trajectory, visibility, removed obstacles and obstacle hit into `result`.
void fillResult(const ScenarioRunner& runner, asg_msgs::RunScenarioResult* result);

std::string formatSeconds(double s);

}  // namespace asg_sim
