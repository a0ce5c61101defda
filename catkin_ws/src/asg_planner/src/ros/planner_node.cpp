// planner: the A* voting planner and PD path follower of the stack under test (docs/planner.md).
#include <ros/ros.h>

#include <cstring>
#include <iostream>

#include "planner_ros.hpp"

int main(int argc, char** argv) {
  if (argc == 2 && std::strcmp(argv[1], "--params") == 0) {  // the table docs/planner.md quotes
    std::cout << asg_planner::plannerNodeParameterTable();
    return 0;
  }
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
