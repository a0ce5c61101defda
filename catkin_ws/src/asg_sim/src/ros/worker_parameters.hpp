#pragma once
/// @file worker_parameters.hpp
/// The scene worker's parameter table: one row per private parameter of the scene_worker node
/// (name as the node reads it, kind, unit, range, whether a stack registration may set it,
/// meaning), in asg_lockstep's table helper (param_table.hpp), which every C++ node uses. The node (scene_worker_params.cpp) reads through it, `scene_worker --params` prints
/// it, and docs/simulator.md quotes that output (tests/test_node_parameters.py), so a parameter,
/// its unit and its range are written here once. Defaults are WorkerParams' own. No ROS.

#include <string>
#include <vector>

#include "asg_lockstep/param_table.hpp"

namespace asg_sim {

/// The scene worker's settings. Defaults here are the node's (scene_worker.yaml states them too).
struct WorkerParams {
  std::vector<std::string> stack_nodes;  ///< nodes that must acknowledge each scenario
  double ack_timeout = 30.0;             ///< [s, wall]
  double command_timeout = 10.0;         ///< [s, wall]
  bool lockstep = true;
  double realtime_factor = 1.0;          ///< [-] free-running mode: simulated s per wall s
  bool publish_labels = true;
  bool odom_every_tick = false;          ///< false: odom/tf only at camera and control ticks
  int render_threads = 1;                ///< [-] llvmpipe threads
  int width = 256, height = 256;         ///< [px]
  double fov_deg = 90.0;                 ///< [deg] horizontal
  int shadow_map_px = 2048;              ///< [px]
  double visibility_full_px = 100.0;     ///< [px]
  std::string labels_node;               ///< node publishing `labels` (named when it falls silent)
  std::string command_interface = "vehicle_command";  ///< or "twist" (cmd_vel, docs/your-stack.md)
  bool publish_points = false;           ///< camera/depth/points: PointCloud2 from depth
  int points_stride = 2;                 ///< [px] pixel step of that cloud in u and v
  bool publish_clock = true;             ///< `clock` (rosgraph_msgs/Clock): this worker's simulated time
  bool publish_map_odom = true;          ///< map -> odom (identity) on tf_static; false: the stack localizes
  // Set by a stack registration only (stack/..., scene_worker_params.cpp), not parameters:
  std::string stack_name;                ///< the registration's stack/name ("": none, ~stack_nodes)
  bool stack_sim_time = false;           ///< the registration's stack/sim_time
  bool stack_acks = true;                ///< false: the stack has no client; its nodes need only be up
};

using WorkerValue = asg_lockstep::params::Value;
using WorkerParameterSpec = asg_lockstep::params::Row;
using WorkerTable = asg_lockstep::params::Table<WorkerParams>;

/// Every parameter, in the order of scene_worker.yaml (asg_lockstep's table helper: kinds, ranges,
/// `--params`; `registration`: a stack registration may set it as stack/worker/NAME, winning
/// over ~NAME).
const WorkerTable& workerParameters();

/// Checks `value` against the row's kind and range and sets it; returns "" or what is wrong,
/// naming the parameter as `where` gives it (e.g. "~camera/width" or "stack/worker/points_stride").
std::string setWorkerParameter(WorkerParams* params, const WorkerParameterSpec& spec, const WorkerValue& value,
                               const std::string& where);

/// Checks across parameters (labels_node among stack_nodes); "" or what is wrong.
std::string checkWorkerParameters(const WorkerParams& params);

/// docs/simulator.md's parameter table, from the table above and the defaults of WorkerParams
/// (stack_nodes has none: the node requires it, scene_worker.yaml gives it).
std::string workerParameterTableMarkdown();

}  // namespace asg_sim
