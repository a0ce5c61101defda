// The scene worker's parameters (private), read and checked once at start; docs/simulator.md
// documents each. A bad value stops the node with a message naming it.
#include <algorithm>

#include "scene_worker_ros.hpp"

namespace asg_sim {

void SceneWorkerROS::readParameters() {
  auto& p = params_;
  if (!pnh_.getParam("stack_nodes", p.stack_nodes) && !nh_.hasParam("stack/name"))
    throw std::runtime_error("parameter ~stack_nodes (list of node names) is required, or a stack registration");
  pnh_.param("ack_timeout", p.ack_timeout, p.ack_timeout);
  pnh_.param("command_timeout", p.command_timeout, p.command_timeout);
  pnh_.param("lockstep", p.lockstep, p.lockstep);
  pnh_.param("realtime_factor", p.realtime_factor, p.realtime_factor);
  pnh_.param("publish_labels", p.publish_labels, p.publish_labels);
  pnh_.param("odom_every_tick", p.odom_every_tick, p.odom_every_tick);
  pnh_.param("render_threads", p.render_threads, p.render_threads);
  pnh_.param("camera/width", p.width, p.width);
  pnh_.param("camera/height", p.height, p.height);
  pnh_.param("camera/fov_deg", p.fov_deg, p.fov_deg);
  pnh_.param("shadow_map_px", p.shadow_map_px, p.shadow_map_px);
  pnh_.param("visibility_full_px", p.visibility_full_px, p.visibility_full_px);
  pnh_.param("labels_node", p.labels_node, p.labels_node);
  pnh_.param("command_interface", p.command_interface, p.command_interface);
  pnh_.param("publish_points", p.publish_points, p.publish_points);
  pnh_.param("points_stride", p.points_stride, p.points_stride);
  pnh_.param("publish_clock", p.publish_clock, p.publish_clock);
  pnh_.param("publish_map_odom", p.publish_map_odom, p.publish_map_odom);
  auto check = [](bool ok, const std::string& what) {
    if (!ok) throw std::runtime_error("bad parameter " + what);
  };
  readRegistration(check);  // before the checks below: a registration's values are checked too
  check(p.ack_timeout > 0, "~ack_timeout: must be > 0 s");
  check(p.command_timeout > 0, "~command_timeout: must be > 0 s");
  check(p.realtime_factor > 0, "~realtime_factor: must be > 0");
  check(p.render_threads >= 1 && p.render_threads <= 64, "~render_threads: must be 1..64");
  check(p.width >= 16 && p.width <= 4096 && p.height >= 16 && p.height <= 4096,
        "~camera/width, ~camera/height: must be 16..4096 px");
  check(p.fov_deg > 1 && p.fov_deg < 179, "~camera/fov_deg: must be in (1, 179)");
  check(p.shadow_map_px >= 256 && p.shadow_map_px <= 8192, "~shadow_map_px: must be 256..8192");
  check(p.visibility_full_px > 0, "~visibility_full_px: must be > 0");
  check(p.labels_node.empty() ||
            std::find(p.stack_nodes.begin(), p.stack_nodes.end(), p.labels_node) != p.stack_nodes.end(),
        "~labels_node: must be one of ~stack_nodes (or empty)");
  check(p.command_interface == "vehicle_command" || p.command_interface == "twist",
        "~command_interface: must be vehicle_command or twist, not '" + p.command_interface + "'");
  check(p.points_stride >= 1 && p.points_stride <= 64, "~points_stride: must be 1..64 px");
}

// A stack registered by its launch file (stacks/*.launch, docs/your-stack.md) sets `stack/...` in
// the worker's namespace: which nodes must be up, the mode, the command interface, simulated
// time, and scene worker parameters it needs (stack/worker/...), which win over ~ and the YAML.
void SceneWorkerROS::readRegistration(const std::function<void(bool, const std::string&)>& check) {
  auto& p = params_;
  if (!nh_.getParam("stack/name", p.stack_name)) return;
  const std::string where = "stack/ (the registration of stack '" + p.stack_name + "'): ";
  check(nh_.getParam("stack/nodes", p.stack_nodes) && !p.stack_nodes.empty(),
        where + "nodes: a list of the stack's node names is required");
  std::string mode = "lockstep";
  nh_.param("stack/mode", mode, mode);
  check(mode == "lockstep" || mode == "free", where + "mode: must be lockstep or free, not '" + mode + "'");
  p.lockstep = mode == "lockstep";
  nh_.param("stack/command", p.command_interface, std::string("vehicle_command"));
  nh_.param("stack/sim_time", p.stack_sim_time, false);
  nh_.param("stack/acks", p.stack_acks, true);
  check(p.stack_acks || !p.lockstep,
        where + "acks: false needs mode: free (in lockstep the stack's client acknowledges and answers each tick)");
  check(!p.stack_sim_time || ros::Time::isSimTime(),
        where + "sim_time: true, but /use_sim_time is false: launch the workers with sim_time:=true "
                "(train.launch) or include asg_bringup/launch/sim_time.launch once");
  nh_.param("stack/worker/publish_points", p.publish_points, p.publish_points);
  nh_.param("stack/worker/points_stride", p.points_stride, p.points_stride);
  nh_.param("stack/worker/publish_labels", p.publish_labels, p.publish_labels);
  nh_.param("stack/worker/labels_node", p.labels_node, p.labels_node);
  nh_.param("stack/worker/publish_map_odom", p.publish_map_odom, p.publish_map_odom);
  nh_.param("stack/worker/publish_clock", p.publish_clock, p.publish_clock);
  nh_.param("stack/worker/realtime_factor", p.realtime_factor, p.realtime_factor);
}

}  // namespace asg_sim
