// An example of a roscpp stack of standard messages made reproducible by the C++ lockstep client
// (docs/your-stack.md): it drives towards the goal (geometry_msgs/PoseStamped) from odometry
// (nav_msgs/Odometry), steering on the heading error, and publishes geometry_msgs/Twist on
// cmd_vel. No perception: obstacles are not seen. The three lines that involve the client are
// marked; the rest is what such a node would be anyway. Its parameters are a table of asg_lockstep's
// helper (param_table.hpp: read by kind and range, `twist_driver --params` prints it).
// tests/cpp_client.test runs it.
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/Twist.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>

#include <algorithm>
#include <cmath>

#include "asg_lockstep/ros/lockstep_client.hpp"
#include "asg_lockstep/ros/param_reader.hpp"

namespace params = asg_lockstep::params;

struct DriverParams {
  double speed = 4.0;         ///< [m/s]
  double gain = 1.5;          ///< [1/s] yaw rate per rad of heading error
  double max_yaw_rate = 0.8;  ///< [rad/s]
};

const params::Table<DriverParams> kTable = {
    {"speed", params::Kind::kReal, "m/s", 0, 30, false, "0..30", "forward speed",
     ASG_PARAM_NUMBER(DriverParams, speed)},
    {"gain", params::Kind::kReal, "1/s", 0, 100, false, "0..100", "yaw rate per rad of heading error",
     ASG_PARAM_NUMBER(DriverParams, gain)},
    {"max_yaw_rate", params::Kind::kReal, "rad/s", 0, 10, false, "0..10", "largest yaw rate",
     ASG_PARAM_NUMBER(DriverParams, max_yaw_rate)},
};

int main(int argc, char** argv) {
  if (params::printedTable(argc, argv, kTable)) return 0;
  ros::init(argc, argv, "twist_driver");
  ros::NodeHandle nh, pnh("~");
  DriverParams p;
  try {
    p = params::readPrivate(pnh, kTable);
  } catch (const std::invalid_argument& e) {
    ROS_FATAL("twist_driver: %s", e.what());
    return 1;
  }
  const double speed = p.speed, gain = p.gain, max_yaw_rate = p.max_yaw_rate;
  bool have_goal = false;
  double gx = 0, gy = 0;

  asg_lockstep::LockstepClient lock(nh, "twist_driver", [&] { have_goal = false; });  // client
  auto cmd = lock.advertiseCmdVel("cmd_vel");                                            // client
  auto goal_sub = lock.subscribe<geometry_msgs::PoseStamped>(                            // client
      "goal", [&](const geometry_msgs::PoseStampedConstPtr& g) {
        gx = g->pose.position.x;
        gy = g->pose.position.y;
        have_goal = true;
      });
  auto odom_sub = lock.subscribe<nav_msgs::Odometry>("odom", [&](const nav_msgs::OdometryConstPtr& o) {
    if (!have_goal) return;
    const auto& q = o->pose.pose.orientation;
    const double yaw = std::atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z));
    double err = std::atan2(gy - o->pose.pose.position.y, gx - o->pose.pose.position.x) - yaw;
    err = std::atan2(std::sin(err), std::cos(err));
    geometry_msgs::Twist t;
    t.linear.x = speed;
    t.angular.z = std::clamp(gain * err, -max_yaw_rate, max_yaw_rate);
    cmd.publish(t);
  });
  ros::spin();
  return 0;
}
