#include "worker_parameters.hpp"

#include <algorithm>
#include <limits>

namespace asg_sim {
namespace {

using K = asg_lockstep::params::Kind;
constexpr double kInf = std::numeric_limits<double>::infinity();

#define ASG_NUMBER(field) ASG_PARAM_NUMBER(WorkerParams, field)
#define ASG_FLAG(field) ASG_PARAM_FLAG(WorkerParams, field)
#define ASG_TEXT(field) ASG_PARAM_TEXT(WorkerParams, field)
#define ASG_LIST(field) ASG_PARAM_LIST(WorkerParams, field)

// Rows: name, kind, unit, lo, hi, open, range text, description, get/set, text choices, number
// choices, whether a registration may set it.
const WorkerTable kTable = {
    {"stack_nodes", K::kList, "-", 0, 0, false, "list of node names",
     "stack nodes that must acknowledge each scenario; required unless a stack registration's `stack/nodes` "
     "replaces it ([your-stack.md](your-stack.md#registering-a-stack))",
     ASG_LIST(stack_nodes), {}, {}, false},
    {"ack_timeout", K::kReal, "s (wall)", 0, kInf, true, "> 0", "limit on waiting for the acknowledgements",
     ASG_NUMBER(ack_timeout), {}, {}, false},
    {"command_timeout", K::kReal, "s (wall)", 0, kInf, true, "> 0",
     "limit on waiting for the command of one control tick", ASG_NUMBER(command_timeout), {}, {}, false},
    {"lockstep", K::kBool, "-", 0, 1, false, "bool",
     "false: free-running (real time x `realtime_factor`, latest command applies, not reproducible); a "
     "registration's `stack/mode` replaces it",
     ASG_FLAG(lockstep), {}, {}, false},
    {"realtime_factor", K::kReal, "-", 0, kInf, true, "> 0",
     "free-running only: simulated seconds per wall second; a lag over 0.25 s behind it is logged",
     ASG_NUMBER(realtime_factor), {}, {}, true},
    {"publish_labels", K::kBool, "-", 0, 1, false, "bool", "publish `camera/labels_gt`",
     ASG_FLAG(publish_labels), {}, {}, true},
    {"odom_every_tick", K::kBool, "-", 0, 1, false, "bool",
     "false: `odom` and `tf` go out at the ticks with a camera frame or a control tick (30 of every 60 per "
     "second), the stamps a stack reads; true: at every 60 Hz tick. The result's trajectory holds every tick "
     "either way",
     ASG_FLAG(odom_every_tick), {}, {}, false},
    {"render_threads", K::kInt, "-", 1, 64, false, "1..64",
     "llvmpipe threads (sets `LP_NUM_THREADS` unless the environment already does)", ASG_NUMBER(render_threads), {}, {}, false},
    {"camera/width", K::kInt, "px", 16, 4096, false, "16..4096", "image width", ASG_NUMBER(width), {}, {}, false},
    {"camera/height", K::kInt, "px", 16, 4096, false, "16..4096", "image height", ASG_NUMBER(height), {}, {}, false},
    {"camera/fov_deg", K::kReal, "deg", 1, 179, true, "(1, 179)", "horizontal field of view",
     ASG_NUMBER(fov_deg), {}, {}, false},
    {"shadow_map_px", K::kInt, "px", 256, 8192, false, "256..8192", "side of the sun's shadow map",
     ASG_NUMBER(shadow_map_px), {}, {}, false},
    {"visibility_full_px", K::kReal, "px", 0, kInf, true, "> 0",
     "pixel count at which an obstacle counts as fully seen", ASG_NUMBER(visibility_full_px), {}, {}, false},
    {"labels_node", K::kText, "-", 0, 0, false, "one of `stack_nodes`, or empty",
     "the stack node publishing `labels` (the segmenter); named when a frame stays unlabelled past "
     "`command_timeout`",
     ASG_TEXT(labels_node), {}, {}, true},
    {"command_interface", K::kText, "-", 0, 0, false, "vehicle_command, twist",
     "what drives the vehicle: `asg_msgs/VehicleCommand` on `cmd` (the paper's stack), or `geometry_msgs/Twist` "
     "on `cmd_vel` through the velocity controller below, lockstep answers as `geometry_msgs/TwistStamped` on "
     "`cmd_vel_stamped` ([your-stack.md](your-stack.md)); a registration's `stack/command` replaces it",
     ASG_TEXT(command_interface), {"vehicle_command", "twist"}, {}, false},
    {"publish_points", K::kBool, "-", 0, 1, false, "bool",
     "publish `camera/depth/points` (`sensor_msgs/PointCloud2`, frame `camera_optical`, x y z float32) from each "
     "depth frame",
     ASG_FLAG(publish_points), {}, {}, true},
    {"points_stride", K::kInt, "px", 1, 64, false, "1..64", "pixel step of that cloud in u and v",
     ASG_NUMBER(points_stride), {}, {}, true},
    {"publish_clock", K::kBool, "-", 0, 1, false, "bool",
     "publish `clock` (`rosgraph_msgs/Clock`): the worker's simulated time", ASG_FLAG(publish_clock), {}, {}, true},
    {"publish_map_odom", K::kBool, "-", 0, 1, false, "bool",
     "`map` -> `odom` (identity) on `tf_static`; false where the stack localizes itself",
     ASG_FLAG(publish_map_odom), {}, {}, true},
};

#undef ASG_NUMBER
#undef ASG_FLAG
#undef ASG_TEXT
#undef ASG_LIST

}  // namespace

const WorkerTable& workerParameters() { return kTable; }

std::string setWorkerParameter(WorkerParams* params, const WorkerParameterSpec& s, const WorkerValue& value,
                               const std::string& where) {
  return asg_lockstep::params::set(kTable, params, s, value, where);
}

std::string checkWorkerParameters(const WorkerParams& p) {
  if (!p.labels_node.empty() &&
      std::find(p.stack_nodes.begin(), p.stack_nodes.end(), p.labels_node) == p.stack_nodes.end())
    return "~labels_node = " + p.labels_node + ": must be one of the stack's nodes (~stack_nodes or the "
           "registration's stack/nodes), or empty";
  return "";
}

std::string workerParameterTableMarkdown() { return asg_lockstep::params::markdown(kTable, true, "required"); }

}  // namespace asg_sim
