#!/usr/bin/env bash
# Prints the benchmark figures recorded in docs/benchmarks.md. One core per process
# (LP_NUM_THREADS=1, taskset), medians over repeats inside each tool; ROS round trips run
# REPEATS times and print each. Builds first if needed.
#   bash scripts/repro/benchmark.sh [REPEATS]
source "$(dirname "${BASH_SOURCE[0]}")/../common.sh"
REPEATS="${1:-3}"
install_packages
build_workspace ON
export LP_NUM_THREADS=1
# the binaries through catkin's workspace search (rosrun), never a devel path
log "simulator core (render, shadow pass, physics, in-process scripted run)"
for e in 1 3; do taskset -c 0 rosrun asg_sim asg_sim_benchmark "$REPO/scenarios/exp$e.yaml" 200 7; done
log "planner core (votes per frame, A* per replan)"
for e in 1 3; do
  # the planner's two shipped configurations: planner.yaml (5 m grids) and its planner_fine.yaml overlay
  CFG="$WS/src/asg_planner/config"
  taskset -c 0 rosrun asg_planner_harness asg_planner_benchmark --repeats 7 --planner "$CFG/planner.yaml" \
    "$REPO/scenarios/exp$e.yaml"
  taskset -c 0 rosrun asg_planner_harness asg_planner_benchmark --repeats 7 --planner "$CFG/planner.yaml" \
    --planner "$CFG/planner_fine.yaml" "$REPO/scenarios/exp$e.yaml"
done
export ROS_MASTER_URI="http://127.0.0.1:${ASG_BENCH_PORT:-11398}" ROS_HOSTNAME=127.0.0.1
TMP="$(mktemp -d)"
export ROS_LOG_DIR="$TMP"
for launch in scripted_worker worker; do
  log "ROS round trip, Exp. 1, lockstep, $launch.launch"
  roslaunch -p "${ROS_MASTER_URI##*:}" "$REPO/launch/$launch.launch" >"$TMP/$launch.log" 2>&1 &
  pid=$!
  for i in $(seq "$REPEATS"); do
    rosrun asg_scenario run_scenario "$REPO/scenarios/exp1.yaml" --out "$TMP/run" --top-down 0 \
      --scenario-id "$((100 + i))" | grep outcome
  done
  kill "$pid"; wait "$pid" 2>/dev/null || true
  sleep 2
done
rm -rf "$TMP"
