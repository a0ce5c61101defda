// The scene worker's parameters (private), read once at start through the node's table
// (worker_parameters.hpp), which docs/simulator.md quotes. Every bad value is named at once, with
// what it must be, and stops the node.
#include "scene_worker_ros.hpp"

namespace asg_sim {
namespace {

// One parameter server value as the row's kind asks; "" or what is wrong with its type.
std::string convert(const XmlRpc::XmlRpcValue& x, const WorkerParameterSpec& s, WorkerValue* v) {
  using K = WorkerParameterSpec::Kind;
  auto t = x.getType();
  XmlRpc::XmlRpcValue copy = x;  // XmlRpcValue's conversions are not const
  switch (s.kind) {
    case K::kBool:
      if (t != XmlRpc::XmlRpcValue::TypeBoolean) return "true or false";
      v->number = bool(copy) ? 1.0 : 0.0;
      return "";
    case K::kInt:
    case K::kReal:
      if (t == XmlRpc::XmlRpcValue::TypeInt) v->number = int(copy);
      else if (t == XmlRpc::XmlRpcValue::TypeDouble) v->number = double(copy);
      else return s.kind == K::kInt ? "a whole number" : "a number";
      return "";
    case K::kText:
      if (t != XmlRpc::XmlRpcValue::TypeString) return "a string";
      v->text = std::string(copy);
      return "";
    case K::kList:
      if (t != XmlRpc::XmlRpcValue::TypeArray) return "a list of node names";
      v->list.clear();
      for (int i = 0; i < copy.size(); ++i) {
        if (copy[i].getType() != XmlRpc::XmlRpcValue::TypeString) return "a list of node names (strings)";
        v->list.push_back(std::string(copy[i]));
      }
      return "";
  }
  return "of a known kind";
}

}  // namespace

// Reads `prefix + row` for every row (`registered_only`: those a registration may set) from `nh`,
// collecting what is wrong in `errors`.
static void readTable(const ros::NodeHandle& nh, const std::string& prefix, const std::string& shown,
                      bool registered_only, WorkerParams* p, std::vector<std::string>* errors) {
  for (const auto& spec : workerParameters()) {
    if (registered_only && !spec.registration) continue;
    XmlRpc::XmlRpcValue x;
    if (!nh.getParam(prefix + spec.name, x)) continue;  // the default stays
    WorkerValue v;
    const std::string where = shown + spec.name;
    std::string why = convert(x, spec, &v);
    if (!why.empty()) {
      errors->push_back(where + ": must be " + why);
      continue;
    }
    why = setWorkerParameter(p, spec, v, where);
    if (!why.empty()) errors->push_back(why);
  }
}

void SceneWorkerROS::readParameters() {
  auto& p = params_;
  std::vector<std::string> errors;
  readTable(pnh_, "", "~", false, &p, &errors);
  if (p.stack_nodes.empty() && !nh_.hasParam("stack/name"))
    errors.push_back("~stack_nodes (list of node names) is required, or a stack registration");
  readRegistration(&errors);  // a registration's values win and are checked the same way
  const std::string across = checkWorkerParameters(p);
  if (!across.empty()) errors.push_back(across);
  if (errors.empty()) return;
  std::string all = "bad parameter";
  all += errors.size() > 1 ? "s: " : ": ";
  for (size_t i = 0; i < errors.size(); ++i) all += (i ? "; " : "") + errors[i];
  throw std::runtime_error(all);
}

// A stack registered by its launch file (stacks/*.launch, docs/your-stack.md) sets `stack/...` in
// the worker's namespace: which nodes must be up, the mode, the command interface, simulated
// time, and the scene worker parameters of the table that a registration may set
// (stack/worker/...), which win over ~ and the YAML.
void SceneWorkerROS::readRegistration(std::vector<std::string>* errors) {
  auto& p = params_;
  if (!nh_.getParam("stack/name", p.stack_name)) return;
  const std::string where = "stack/ (the registration of stack '" + p.stack_name + "'): ";
  auto check = [&](bool ok, const std::string& what) {
    if (!ok) errors->push_back(where + what);
  };
  check(nh_.getParam("stack/nodes", p.stack_nodes) && !p.stack_nodes.empty(),
        "nodes: a list of the stack's node names is required");
  std::string mode = "lockstep";
  nh_.param("stack/mode", mode, mode);
  check(mode == "lockstep" || mode == "free", "mode: must be lockstep or free, not '" + mode + "'");
  p.lockstep = mode == "lockstep";
  nh_.param("stack/command", p.command_interface, std::string("vehicle_command"));
  check(p.command_interface == "vehicle_command" || p.command_interface == "twist",
        "command: must be vehicle_command or twist, not '" + p.command_interface + "'");
  nh_.param("stack/sim_time", p.stack_sim_time, false);
  nh_.param("stack/acks", p.stack_acks, true);
  check(p.stack_acks || !p.lockstep,
        "acks: false needs mode: free (in lockstep the stack's client acknowledges and answers each tick)");
  check(!p.stack_sim_time || ros::Time::isSimTime(),
        "sim_time: true, but /use_sim_time is false: launch the workers with sim_time:=true "
        "(train.launch) or include asg_bringup/launch/sim_time.launch once");
  readTable(nh_, "stack/worker/", "stack/worker/", true, &p, errors);
}

}  // namespace asg_sim
