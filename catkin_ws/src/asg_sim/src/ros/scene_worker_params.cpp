// The scene worker's parameters (private), read once at start through the node's table
// (worker_parameters.hpp), which docs/simulator.md quotes. Every bad value is named at once, with
// what it must be, and stops the node.
#include "scene_worker_ros.hpp"

#include "asg_lockstep/ros/param_reader.hpp"

namespace asg_sim {

namespace params = asg_lockstep::params;

void SceneWorkerROS::readParameters() {
  auto& p = params_;
  std::vector<std::string> errors;
  params::readTable(pnh_, "", "~", workerParameters(), &p, &errors);
  if (p.stack_nodes.empty() && !nh_.hasParam("stack/name"))
    errors.push_back("~stack_nodes (list of node names) is required, or a stack registration");
  readRegistration(&errors);  // a registration's values win and are checked the same way
  const std::string across = checkWorkerParameters(p);
  if (!across.empty()) errors.push_back(across);
  if (!errors.empty()) throw std::runtime_error(params::joinErrors(errors));
}

// A stack registered by its launch file (stacks/*.launch, docs/your-stack.md) sets `stack/...` in
// the worker's namespace: which nodes must be up, the mode, the command interface, simulated
// time, and the scene worker parameters of the table that a registration may set
// (stack/worker/...), which win over ~ and the YAML.
void SceneWorkerROS::readRegistration(std::vector<std::string>* errors) {
  auto& p = params_;
  using params::Kind;
  params::Value v;
  if (!params::readOne(nh_, "stack/name", Kind::kText, &v, errors)) return;
  p.stack_name = v.text;
  const std::string where = "stack/ (the registration of stack '" + p.stack_name + "'): ";
  auto check = [&](bool ok, const std::string& what) {
    if (!ok) errors->push_back(where + what);
  };
  // Each key is read as its kind: a string for sim_time, say, is refused by name, not taken as
  // the default (NodeHandle::param would keep it silently).
  const size_t before = errors->size();
  const bool nodes = params::readOne(nh_, "stack/nodes", Kind::kList, &v, errors);
  if (nodes) p.stack_nodes = v.list;
  check(errors->size() > before || (nodes && !v.list.empty()),
        "nodes: a list of the stack's node names is required");
  std::string mode = "lockstep";
  if (params::readOne(nh_, "stack/mode", Kind::kText, &v, errors)) mode = v.text;
  check(mode == "lockstep" || mode == "free", "mode: must be lockstep or free, not '" + mode + "'");
  p.lockstep = mode == "lockstep";
  p.command_interface = "vehicle_command";
  if (params::readOne(nh_, "stack/command", Kind::kText, &v, errors)) p.command_interface = v.text;
  check(p.command_interface == "vehicle_command" || p.command_interface == "twist",
        "command: must be vehicle_command or twist, not '" + p.command_interface + "'");
  p.stack_sim_time = false;
  if (params::readOne(nh_, "stack/sim_time", Kind::kBool, &v, errors)) p.stack_sim_time = v.number != 0.0;
  p.stack_acks = true;
  if (params::readOne(nh_, "stack/acks", Kind::kBool, &v, errors)) p.stack_acks = v.number != 0.0;
  check(p.stack_acks || !p.lockstep,
        "acks: false needs mode: free (in lockstep the stack's client acknowledges and answers each tick)");
  check(!p.stack_sim_time || ros::Time::isSimTime(),
        "sim_time: true, but /use_sim_time is false: launch the workers with sim_time:=true "
        "(train.launch) or include asg_bringup/launch/sim_time.launch once");
  params::readTable(nh_, "stack/worker/", "stack/worker/", workerParameters(), &p, errors,
                    [](const params::Row& r) { return r.registration; });
}

}  // namespace asg_sim
