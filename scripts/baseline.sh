#!/usr/bin/env bash
# Issue #23, the baseline: the ground-truth-label stack and the flawed and full U-Net stacks on
# the same seeded random layouts of an experiment (uniform random search, seed 0), two workers
# per stack. Resumable: each stack appends to results/baseline/<exp>/<stack>.jsonl as runs end.
# Writes results/baseline/<exp>.json and prints the table of docs/baseline.md.
#   bash scripts/baseline.sh EXPERIMENT [N_GROUND_TRUTH=500] [N_UNET=300]
#   e.g. bash scripts/baseline.sh exp1      (experiments/exp1.yaml)
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
EXP="${1:?usage: baseline.sh EXPERIMENT [N_GROUND_TRUTH] [N_UNET]}"
[ -f "$EXP" ] || EXP="$REPO/experiments/$EXP.yaml"
[ -f "$EXP" ] || { echo "baseline.sh: no experiment file $1 (nor $EXP)" >&2; exit 2; }
N_GT="${2:-500}"
N_UNET="${3:-300}"
install_packages
build_workspace ON
export ROS_MASTER_URI="http://127.0.0.1:${ASG_BASELINE_PORT:-11395}" ROS_HOSTNAME=127.0.0.1 ROS_IP=127.0.0.1
export LP_NUM_THREADS=1 ROS_LOG_DIR="$REPO/runs/baseline/logs"
PORT="${ROS_MASTER_URI##*:}"
CFG="${ASG_PLANNER_CONFIG:-$WS/src/asg_planner/config/planner.yaml}"
for spec in ground_truth:"$N_GT" flawed:"$N_UNET" full:"$N_UNET"; do
  stack="${spec%%:*}"; n="${spec##*:}"
  [ "$n" -gt 0 ] || continue
  args=(perception:=unet model:="$stack")
  [ "$stack" = ground_truth ] && args=(perception:=ground_truth)
  log "$(basename "$EXP" .yaml): $stack stack, $n layouts"
  roscore -p "$PORT" >/dev/null 2>&1 & core=$!
  sleep 3
  pids=()
  for w in 0 1; do
    roslaunch "$REPO/launch/worker.launch" ns:="worker_$w" "${args[@]}" planner_config:="$CFG" markers:=false \
        >/dev/null 2>&1 & pids+=($!)
  done
  status=0
  /usr/bin/python3 -m asg_agent.baseline run "$EXP" --stack "$stack" --layouts "$n" --workers 2 || status=$?
  kill "${pids[@]}" 2>/dev/null; wait "${pids[@]}" 2>/dev/null || true
  kill "$core"; wait "$core" 2>/dev/null || true
  [ "$status" -eq 0 ] || exit "$status"
done
/usr/bin/python3 -m asg_agent.baseline summary "$EXP"
