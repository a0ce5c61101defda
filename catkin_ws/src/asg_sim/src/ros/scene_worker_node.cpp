// scene_worker: builds off-road scenes on request, renders and simulates them in lockstep with
// the autonomy stack in the same namespace (docs/simulator.md).
#include <ros/ros.h>

#include <cstring>
#include <iostream>

#include "scene_worker_ros.hpp"

int main(int argc, char** argv) {
  if (argc == 2 && std::strcmp(argv[1], "--params") == 0) {  // the table docs/simulator.md quotes
    std::cout << asg_sim::workerParameterTableMarkdown();
    return 0;
  }
  ros::init(argc, argv, "scene_worker");
  ros::NodeHandle nh, pnh("~");
  try {
    asg_sim::SceneWorkerROS worker(nh, pnh);
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL("scene_worker: %s", e.what());
    return 1;
  }
  return 0;
}
