#!/usr/bin/env bash
# Issue #11, "is a finding the flaw's fault or the layout's?": the top N scenarios of the flawed
# Exp. 1 campaign run again on the full-model stack and on the ground-truth-label stack, with the
# paper's 5 m planner grids (planner.yaml, the campaign's) and with the fine grids
# (planner_fine.yaml, where the flawed stack is re-run too). Two workers per stack; results under
# results/flaw_or_layout/, the table in docs/experiments.md (python3 -m asg_analysis experiments).
#   bash scripts/repro/flaw_or_layout.sh [EXPORT=results/campaigns/exp1-td3-per-asp-s0.jsonl.gz] [TOP=50]
# ASG_RERUN_OUT=results/NAME: another results folder (its table: results/NAME.json).
# ASG_RERUN_SELECT=perception: an attributed campaign's perception findings, differential findings
#   and perception collisions instead of the top N by proxy (asg_agent.ros.rerun --select).
# ASG_RERUN_STACKS="GRID:STACK ...": which re-runs (default: all five below). Round 3's (issue #25):
#   ASG_RERUN_OUT=results/flaw_or_layout_round3 ASG_RERUN_SELECT=perception \
#   ASG_RERUN_STACKS="paper:full fine:flawed fine:ground_truth" bash scripts/repro/flaw_or_layout.sh \
#       results/comparison/exp1b-td3-per-asp-s0.jsonl.gz 200
source "$(dirname "${BASH_SOURCE[0]}")/../common.sh"
EXPORT="${1:-$REPO/results/campaigns/exp1-td3-per-asp-s0.jsonl.gz}"
TOP="${2:-50}"
install_packages
build_workspace ON
OUT="$REPO/${ASG_RERUN_OUT:-results/flaw_or_layout}"
mkdir -p "$OUT"
use_local_master "${ASG_RERUN_PORT:-11396}" "$REPO/runs/flaw_or_layout/logs"
trap 'stop_workers; stop_master' EXIT
CFG="$WS/src/asg_planner/config"
SELECT="${ASG_RERUN_SELECT:-proxy}"
for spec in ${ASG_RERUN_STACKS:-paper:full paper:ground_truth fine:flawed fine:full fine:ground_truth}; do
  grid="${spec%%:*}"; stack="${spec##*:}"
  [ -f "$OUT/$grid-$stack.jsonl" ] && { log "$grid/$stack: done before, kept"; continue; }
  cfg="$CFG/planner.yaml"; [ "$grid" = fine ] && cfg="$CFG/planner_fine.yaml"
  args=(perception:=unet model:="$stack")
  [ "$stack" = ground_truth ] && args=(perception:=ground_truth)
  log "$grid grid, $stack stack: top $TOP ($SELECT) of $(basename "$EXPORT")"
  start_master
  start_workers 2 "${args[@]}" planner_config:="$cfg"
  /usr/bin/python3 -m asg_agent.ros.rerun run "$EXPORT" --top "$TOP" --select "$SELECT" --workers 2 --label "$grid/$stack" \
      --out "$OUT/$grid-$stack.jsonl.part" && mv "$OUT/$grid-$stack.jsonl.part" "$OUT/$grid-$stack.jsonl"
  stop_workers
  stop_master
done
/usr/bin/python3 -m asg_agent.ros.rerun summary "$OUT"/*.jsonl --json "$OUT.json"
