#!/usr/bin/env bash
# Issue #11, "is a finding the flaw's fault or the layout's?": the top N scenarios of the flawed
# Exp. 1 campaign run again on the full-model stack and on the ground-truth-label stack, with the
# paper's 5 m planner grids (planner.yaml, the campaign's) and with the fine grids
# (planner_fine.yaml, where the flawed stack is re-run too). Two workers per stack; results under
# results/flaw_or_layout/, the table in docs/experiments.md (python3 -m asg_agent.experiments).
#   bash scripts/flaw_or_layout.sh [EXPORT=results/campaigns/exp1-td3-per-asp-s0.jsonl.gz] [TOP=50]
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
EXPORT="${1:-$REPO/results/campaigns/exp1-td3-per-asp-s0.jsonl.gz}"
TOP="${2:-50}"
install_packages
build_workspace ON
OUT="$REPO/results/flaw_or_layout"
mkdir -p "$OUT"
export ROS_MASTER_URI="http://127.0.0.1:${ASG_RERUN_PORT:-11396}" ROS_HOSTNAME=127.0.0.1 ROS_IP=127.0.0.1
export LP_NUM_THREADS=1 ROS_LOG_DIR="$REPO/runs/flaw_or_layout/logs"
PORT="${ROS_MASTER_URI##*:}"
CFG="$WS/src/asg_planner/config"
for spec in paper:full paper:ground_truth fine:flawed fine:full fine:ground_truth; do
  grid="${spec%%:*}"; stack="${spec##*:}"
  [ -f "$OUT/$grid-$stack.jsonl" ] && { log "$grid/$stack: done before, kept"; continue; }
  cfg="$CFG/planner.yaml"; [ "$grid" = fine ] && cfg="$CFG/planner_fine.yaml"
  args=(perception:=unet model:="$stack")
  [ "$stack" = ground_truth ] && args=(perception:=ground_truth)
  log "$grid grid, $stack stack: top $TOP of $(basename "$EXPORT")"
  roscore -p "$PORT" >/dev/null 2>&1 & core=$!
  sleep 3
  pids=()
  for w in 0 1; do
    roslaunch "$REPO/launch/worker.launch" ns:="worker_$w" "${args[@]}" planner_config:="$cfg" markers:=false \
        >/dev/null 2>&1 & pids+=($!)
  done
  /usr/bin/python3 -m asg_agent.rerun run "$EXPORT" --top "$TOP" --workers 2 --label "$grid/$stack" \
      --out "$OUT/$grid-$stack.jsonl.part" && mv "$OUT/$grid-$stack.jsonl.part" "$OUT/$grid-$stack.jsonl"
  kill "${pids[@]}" 2>/dev/null; wait "${pids[@]}" 2>/dev/null
  kill "$core"; wait "$core" 2>/dev/null || true
done
/usr/bin/python3 -m asg_agent.rerun summary "$OUT"/*.jsonl --json "$REPO/results/flaw_or_layout.json"
