// wall_clock: the master's /clock when stacks run on simulated time (issue #55). Each scene worker
// publishes its own simulated time on <worker>/clock, which the nodes of its stack hear as /clock
// (worker.launch remaps it); everything else on the master (the scene workers' action servers,
// the campaign, the tools) keeps the wall clock through this node, at ~rate [Hz].
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>

int main(int argc, char** argv) {
  ros::init(argc, argv, "wall_clock");
  ros::NodeHandle nh, pnh("~");
  double rate = 100.0;  // [Hz]
  pnh.param("rate", rate, rate);
  if (!(rate >= 1.0 && rate <= 1000.0)) {
    ROS_FATAL("wall_clock: bad parameter ~rate = %g: must be 1..1000 Hz", rate);
    return 1;
  }
  ros::Publisher pub = nh.advertise<rosgraph_msgs::Clock>("/clock", 4);
  ros::WallRate r(rate);
  rosgraph_msgs::Clock c;
  while (ros::ok()) {
    const ros::WallTime now = ros::WallTime::now();
    c.clock = ros::Time(now.sec, now.nsec);
    pub.publish(c);
    r.sleep();
  }
  return 0;
}
