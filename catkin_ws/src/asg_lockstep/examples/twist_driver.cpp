// An example of a roscpp stack of standard messages made reproducible by the C++ lockstep client
// (docs/your-stack.md): it drives towards the goal (geometry_msgs/PoseStamped) from odometry
// (nav_msgs/Odometry), steering on the heading error, and publishes geometry_msgs/Twist on
// cmd_vel. No perception: obstacles are not seen. The three lines that involve the client are
// marked; the rest is what such a node would be anyway. tests/cpp_client.test runs it.
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/Twist.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>

#include <algorithm>
#include <cmath>

#include "asg_lockstep/ros/lockstep_client.hpp"

int main(int argc, char** argv) {
  ros::init(argc, argv, "twist_driver");
  ros::NodeHandle nh, pnh("~");
  double speed = 4.0, gain = 1.5, max_yaw_rate = 0.8;
  pnh.param("speed", speed, speed);                // [m/s]
  pnh.param("gain", gain, gain);                   // [1/s] yaw rate per rad of heading error
  pnh.param("max_yaw_rate", max_yaw_rate, max_yaw_rate);  // [rad/s]
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
