// planner: the A* voting planner and PD path follower of the stack under test (docs/planner.md).
#include <ros/ros.h>

#include "planner_ros.hpp"

int main(int argc, char** argv) {
  ros::init(argc, argv, "planner");
  ros::NodeHandle nh, pnh("~");
  try {
    asg_planner::PlannerROS planner(nh, pnh);
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL("planner: %s", e.what());
    return 1;
  }
  return 0;
}
