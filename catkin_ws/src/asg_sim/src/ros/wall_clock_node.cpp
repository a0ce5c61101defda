// wall_clock: the master's /clock when stacks run on simulated time (issue #55). Each scene worker
// publishes its own simulated time on <worker>/clock, which the nodes of its stack hear as /clock
// (worker.launch remaps it); everything else on the master (the scene workers' action servers,
// the campaign, the tools) keeps the wall clock through this node. Its parameters are the table
// below (issue #56): the node reads through it and `wall_clock --params` prints what
// docs/your-stack.md quotes (tests/test_node_parameters.py).
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <string>

namespace {

/// A real private parameter: [lo, hi] inclusive.
struct RealParameter {
  const char* name;
  const char* unit;
  double default_value, lo, hi;
  const char* description;
};

constexpr RealParameter kParameters[] = {
    {"rate", "Hz (wall)", 100.0, 1.0, 1000.0, "how often `/clock` is published, from the wall clock"},
};

void printTable() {
  std::printf("| parameter | unit | default | range | meaning |\n|---|---|---|---|---|\n");
  for (const RealParameter& p : kParameters)
    std::printf("| `%s` | %s | %.1f | %g..%g | %s |\n", p.name, p.unit, p.default_value, p.lo, p.hi, p.description);
}

/// The parameter's value (its default when unset); sets *error, naming it, when the value is not
/// a number in its range.
double readReal(const ros::NodeHandle& pnh, const RealParameter& p, std::string* error) {
  XmlRpc::XmlRpcValue v;
  if (!pnh.getParam(p.name, v)) return p.default_value;
  double x = NAN;
  std::ostringstream shown;
  if (v.getType() == XmlRpc::XmlRpcValue::TypeDouble) shown << (x = static_cast<double>(v));
  else if (v.getType() == XmlRpc::XmlRpcValue::TypeInt) shown << (x = static_cast<int>(v));
  else if (v.getType() == XmlRpc::XmlRpcValue::TypeString) shown << "'" << static_cast<std::string>(v) << "'";
  else shown << v.toXml();
  if (!(x >= p.lo && x <= p.hi)) {  // NaN (a value of another kind) fails too
    std::ostringstream out;
    out << "bad parameter ~" << p.name << " = " << shown.str() << ": must be a number in " << p.lo << ".." << p.hi
        << " [" << p.unit << "]";
    *error = out.str();
  }
  return x;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 2 && std::strcmp(argv[1], "--params") == 0) {
    printTable();
    return 0;
  }
  ros::init(argc, argv, "wall_clock");
  ros::NodeHandle nh, pnh("~");
  std::string error;
  const double rate = readReal(pnh, kParameters[0], &error);  // [Hz]
  if (!error.empty()) {
    ROS_FATAL("wall_clock: %s", error.c_str());
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
