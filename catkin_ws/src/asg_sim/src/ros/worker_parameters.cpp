#include "worker_parameters.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace asg_sim {
namespace {

using K = WorkerParameterSpec::Kind;
constexpr double kInf = std::numeric_limits<double>::infinity();

// get/set of one field, as captureless lambdas (function pointers).
#define ASG_NUMBER(field)                                                                       \
  [](const WorkerParams& p) { WorkerValue v; v.number = double(p.field); return v; },          \
      [](WorkerParams* p, const WorkerValue& v) { p->field = decltype(p->field)(v.number); }
#define ASG_FLAG(field)                                                                         \
  [](const WorkerParams& p) { WorkerValue v; v.number = p.field ? 1.0 : 0.0; return v; },      \
      [](WorkerParams* p, const WorkerValue& v) { p->field = v.number != 0.0; }
#define ASG_TEXT(field)                                                                         \
  [](const WorkerParams& p) { WorkerValue v; v.text = p.field; return v; },                    \
      [](WorkerParams* p, const WorkerValue& v) { p->field = v.text; }
#define ASG_LIST(field)                                                                         \
  [](const WorkerParams& p) { WorkerValue v; v.list = p.field; return v; },                    \
      [](WorkerParams* p, const WorkerValue& v) { p->field = v.list; }

const std::vector<WorkerParameterSpec> kTable = {
    {"stack_nodes", K::kList, "-", 0, 0, false, "list of node names", false,
     "stack nodes that must acknowledge each scenario; required unless a stack registration's `stack/nodes` "
     "replaces it ([your-stack.md](your-stack.md#registering-a-stack))",
     ASG_LIST(stack_nodes)},
    {"ack_timeout", K::kReal, "s (wall)", 0, kInf, true, "> 0", false, "limit on waiting for the acknowledgements",
     ASG_NUMBER(ack_timeout)},
    {"command_timeout", K::kReal, "s (wall)", 0, kInf, true, "> 0", false,
     "limit on waiting for the command of one control tick", ASG_NUMBER(command_timeout)},
    {"lockstep", K::kBool, "-", 0, 1, false, "bool", false,
     "false: free-running (real time x `realtime_factor`, latest command applies, not reproducible); a "
     "registration's `stack/mode` replaces it",
     ASG_FLAG(lockstep)},
    {"realtime_factor", K::kReal, "-", 0, kInf, true, "> 0", true,
     "free-running only: simulated seconds per wall second; a lag over 0.25 s behind it is logged",
     ASG_NUMBER(realtime_factor)},
    {"publish_labels", K::kBool, "-", 0, 1, false, "bool", true, "publish `camera/labels_gt`",
     ASG_FLAG(publish_labels)},
    {"odom_every_tick", K::kBool, "-", 0, 1, false, "bool", false,
     "false: `odom` and `tf` go out at the ticks with a camera frame or a control tick (30 of every 60 per "
     "second), the stamps a stack reads; true: at every 60 Hz tick. The result's trajectory holds every tick "
     "either way",
     ASG_FLAG(odom_every_tick)},
    {"render_threads", K::kInt, "-", 1, 64, false, "1..64", false,
     "llvmpipe threads (sets `LP_NUM_THREADS` unless the environment already does)", ASG_NUMBER(render_threads)},
    {"camera/width", K::kInt, "px", 16, 4096, false, "16..4096", false, "image width", ASG_NUMBER(width)},
    {"camera/height", K::kInt, "px", 16, 4096, false, "16..4096", false, "image height", ASG_NUMBER(height)},
    {"camera/fov_deg", K::kReal, "deg", 1, 179, true, "(1, 179)", false, "horizontal field of view",
     ASG_NUMBER(fov_deg)},
    {"shadow_map_px", K::kInt, "px", 256, 8192, false, "256..8192", false, "side of the sun's shadow map",
     ASG_NUMBER(shadow_map_px)},
    {"visibility_full_px", K::kReal, "px", 0, kInf, true, "> 0", false,
     "pixel count at which an obstacle counts as fully seen", ASG_NUMBER(visibility_full_px)},
    {"labels_node", K::kText, "-", 0, 0, false, "one of `stack_nodes`, or empty", true,
     "the stack node publishing `labels` (the segmenter); named when a frame stays unlabelled past "
     "`command_timeout`",
     ASG_TEXT(labels_node)},
    {"command_interface", K::kText, "-", 0, 0, false, "vehicle_command, twist", false,
     "what drives the vehicle: `asg_msgs/VehicleCommand` on `cmd` (the paper's stack), or `geometry_msgs/Twist` "
     "on `cmd_vel` through the velocity controller below, lockstep answers as `geometry_msgs/TwistStamped` on "
     "`cmd_vel_stamped` ([your-stack.md](your-stack.md)); a registration's `stack/command` replaces it",
     ASG_TEXT(command_interface), {"vehicle_command", "twist"}},
    {"publish_points", K::kBool, "-", 0, 1, false, "bool", true,
     "publish `camera/depth/points` (`sensor_msgs/PointCloud2`, frame `camera_optical`, x y z float32) from each "
     "depth frame",
     ASG_FLAG(publish_points)},
    {"points_stride", K::kInt, "px", 1, 64, false, "1..64", true, "pixel step of that cloud in u and v",
     ASG_NUMBER(points_stride)},
    {"publish_clock", K::kBool, "-", 0, 1, false, "bool", true,
     "publish `clock` (`rosgraph_msgs/Clock`): the worker's simulated time", ASG_FLAG(publish_clock)},
    {"publish_map_odom", K::kBool, "-", 0, 1, false, "bool", true,
     "`map` -> `odom` (identity) on `tf_static`; false where the stack localizes itself",
     ASG_FLAG(publish_map_odom)},
};

#undef ASG_NUMBER
#undef ASG_FLAG
#undef ASG_TEXT
#undef ASG_LIST

std::string number(double v, bool integral) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), integral ? "%.0f" : "%.15g", v);
  std::string s = buf;
  if (!integral && s.find_first_of(".en") == std::string::npos) s += ".0";
  return s;
}

}  // namespace

const std::vector<WorkerParameterSpec>& workerParameters() { return kTable; }

std::string formatWorkerValue(const WorkerParameterSpec& spec, const WorkerValue& value) {
  switch (spec.kind) {
    case K::kBool:
      return value.number != 0.0 ? "true" : "false";
    case K::kInt:
      return number(value.number, true);
    case K::kReal:
      return number(value.number, false);
    case K::kText:
      return value.text.empty() ? "`\"\"`" : value.text;
    case K::kList: {
      std::string s = "`[";
      for (size_t i = 0; i < value.list.size(); ++i) s += (i ? ", " : "") + value.list[i];
      return s + "]`";
    }
  }
  return "";
}

std::string setWorkerParameter(WorkerParams* params, const WorkerParameterSpec& s, const WorkerValue& value,
                               const std::string& where) {
  auto bad = [&](const std::string& must) {
    return where + " = " + formatWorkerValue(s, value) + ": must be " + must;
  };
  const double v = value.number;
  if (s.kind == K::kReal || s.kind == K::kInt) {
    if (!std::isfinite(v)) return bad("a finite number");
    if (s.kind == K::kInt && v != std::floor(v)) return bad("a whole number");
    const bool in = s.open ? (v > s.lo && v < s.hi) : (v >= s.lo && v <= s.hi);
    if (!in) return bad(std::string("in ") + s.range_text + (s.unit[0] == '-' ? "" : std::string(" [") + s.unit + "]"));
  } else if (s.kind == K::kBool && v != 0.0 && v != 1.0) {
    return bad("true or false");
  } else if (s.kind == K::kText && !s.choices.empty() &&
             std::find(s.choices.begin(), s.choices.end(), value.text) == s.choices.end()) {
    return bad(std::string("one of ") + s.range_text);
  } else if (s.kind == K::kList) {
    for (const auto& name : value.list)
      if (name.empty()) return bad("a list of node names (one is empty)");
  }
  s.set(params, value);
  return "";
}

std::string checkWorkerParameters(const WorkerParams& p) {
  if (!p.labels_node.empty() &&
      std::find(p.stack_nodes.begin(), p.stack_nodes.end(), p.labels_node) == p.stack_nodes.end())
    return "~labels_node = " + p.labels_node + ": must be one of the stack's nodes (~stack_nodes or the "
           "registration's stack/nodes), or empty";
  return "";
}

std::string workerParameterTableMarkdown() {
  const WorkerParams defaults;
  std::string out =
      "| parameter | unit | default | range | a registration may set it | meaning |\n"
      "|---|---|---|---|---|---|\n";
  for (const auto& s : kTable) {
    std::string value = s.kind == K::kList && defaults.stack_nodes.empty()
                            ? std::string("required")
                            : formatWorkerValue(s, s.get(defaults));
    out += std::string("| `") + s.name + "` | " + s.unit + " | " + value + " | " + s.range_text + " | " +
           (s.registration ? "yes" : "-") + " | " + s.description + " |\n";
  }
  return out;
}

}  // namespace asg_sim
