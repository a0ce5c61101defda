#!/usr/bin/env bash
# The main job on its default settings: install what is missing, build, then run a scenario
# file (default: the paper's Exp. 1) through one scene worker and its autonomy stack, print the
# outcome and write the trajectory and a picture to runs/demo/. Idempotent.
#   bash scripts/demo.sh [SCENARIO.yaml] [OUT_DIR]
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
SCENARIO="$(realpath "${1:-$REPO/scenarios/exp1.yaml}")"
OUT="$(realpath -m "${2:-$REPO/runs/demo}")"
install_packages
build_workspace ON
# A master of our own on a port of our own: a user's running roscore is left alone.
LOG="$OUT/logs"
use_local_master "${ASG_DEMO_PORT:-11399}" "$LOG"
log "starting worker_0 and its stack (logs: $LOG)"
roslaunch -p "${ROS_MASTER_URI##*:}" "$REPO/launch/worker.launch" >"$LOG/roslaunch.log" 2>&1 &
LAUNCH_PID=$!
trap 'kill $LAUNCH_PID 2>/dev/null; wait $LAUNCH_PID 2>/dev/null || true' EXIT
log "running $SCENARIO"
rosrun asg_scenario run_scenario "$SCENARIO" --worker /worker_0 --out "$OUT"
log "done: $OUT/run.png shows the run"
