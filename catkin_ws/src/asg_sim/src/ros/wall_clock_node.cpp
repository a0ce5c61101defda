// wall_clock: the master's /clock when stacks run on simulated time (issue #55). Each scene worker
// publishes its own simulated time on <worker>/clock, which the nodes of its stack hear as /clock
// (worker.launch remaps it); everything else on the master (the scene workers' action servers,
// the campaign, the tools) keeps the wall clock through this node. Its parameters are the table
// below (issue #56): the node reads through it and `wall_clock --params` prints what
// docs/your-stack.md quotes (tests/test_node_parameters.py).
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>

#include <stdexcept>
#include <vector>

#include "asg_lockstep/ros/param_reader.hpp"

namespace {

namespace params = asg_lockstep::params;

struct WallClockParams {
  double rate = 100.0;  ///< [Hz, wall]
};

const params::Table<WallClockParams> kTable = {
    {"rate", params::Kind::kReal, "Hz (wall)", 1.0, 1000.0, false, "1..1000",
     "how often `/clock` is published, from the wall clock", ASG_PARAM_NUMBER(WallClockParams, rate)},
};

}  // namespace

int main(int argc, char** argv) {
  if (params::printedTable(argc, argv, kTable)) return 0;
  ros::init(argc, argv, "wall_clock");
  ros::NodeHandle nh, pnh("~");
  WallClockParams p;
  try {
    p = params::readPrivate(pnh, kTable);
  } catch (const std::invalid_argument& e) {
    ROS_FATAL("wall_clock: %s", e.what());
    return 1;
  }
  ros::Publisher pub = nh.advertise<rosgraph_msgs::Clock>("/clock", 4);
  ros::WallRate r(p.rate);
  rosgraph_msgs::Clock c;
  while (ros::ok()) {
    const ros::WallTime now = ros::WallTime::now();
    c.clock = ros::Time(now.sec, now.nsec);
    pub.publish(c);
    r.sleep();
  }
  return 0;
}
