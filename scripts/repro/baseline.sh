#!/usr/bin/env bash
# Issue #23, the baseline: the ground-truth-label stack and the flawed and full U-Net stacks on
# the same seeded random layouts of an experiment (uniform random search, seed 0), two workers
# per stack. Resumable: each stack appends to results/baseline/<exp>/<stack>.jsonl as runs end.
# Writes results/baseline/<exp>.json and prints the table of docs/baseline.md.
#   bash scripts/repro/baseline.sh EXPERIMENT [N_GROUND_TRUTH=500] [N_UNET=300]
#   e.g. bash scripts/repro/baseline.sh exp1      (experiments/exp1.yaml)
# ASG_PLANNER_CONFIG=FILE: another planner configuration. ASG_UNET_BACKEND: the U-Net stacks'
# inference backend, default the shipped one (asg_perception.numerics.DEFAULT_BACKEND: fp32
# polyphase since issue #53; bf16 from issue #24 to #53, channels_last before); channels_last rows
# are in results/baseline/<exp>/, another backend's in results/baseline/backend_<B>/<exp>/, which
# share the ground-truth rows of the first (compare with python3 -m asg_agent.cli.baseline
# compare; polyphase's equal channels_last's, docs/baseline.md "Numerics"). ASG_BASELINE_STACKS="flawed": only those stacks
# (default "ground_truth flawed full"; the lite pair: "flawed_lite full_lite"; the pair trained
# with terrain and weather, issue #27: "flawed_tw full_tw"; the depth stack of issue #39, on
# workers launched with stack:=depth: "depth", N_UNET layouts; the hardened models of issue #40:
# "flawed_hf1 flawed_hr1"; gap_nav, issue #55, on simulated time: "gap_nav", N_UNET layouts).
source "$(dirname "${BASH_SOURCE[0]}")/../common.sh"
EXP="${1:?usage: baseline.sh EXPERIMENT [N_GROUND_TRUTH] [N_UNET]}"
[ -f "$EXP" ] || EXP="$REPO/experiments/$EXP.yaml"
[ -f "$EXP" ] || { echo "baseline.sh: no experiment file $1 (nor $EXP)" >&2; exit 2; }
N_GT="${2:-500}"
N_UNET="${3:-300}"
install_packages
build_workspace ON
use_local_master "${ASG_BASELINE_PORT:-11395}" "$REPO/runs/baseline/logs"
CFG="${ASG_PLANNER_CONFIG:-$WS/src/asg_planner/config/planner.yaml}"
BACKEND="${ASG_UNET_BACKEND:-$(/usr/bin/python3 -c 'from asg_perception.numerics import DEFAULT_BACKEND as d; print(d)')}"
ROOT=()
[ "$BACKEND" = channels_last ] || ROOT=(--root "$REPO/results/baseline/backend_$BACKEND")
GT_ROOT=(--ground-truth-root "$REPO/results/baseline")
trap 'stop_workers; stop_master' EXIT
for spec in ground_truth:"$N_GT" flawed:"$N_UNET" full:"$N_UNET" flawed_lite:"$N_UNET" full_lite:"$N_UNET" \
    flawed_tw:"$N_UNET" full_tw:"$N_UNET" depth:"$N_UNET" flawed_hf1:"$N_UNET" flawed_hr1:"$N_UNET" \
    gap_nav:"$N_UNET"; do
  stack="${spec%%:*}"; n="${spec##*:}"
  [ "$n" -gt 0 ] || continue
  [[ " ${ASG_BASELINE_STACKS:-ground_truth flawed full} " == *" $stack "* ]] || continue
  args=(perception:=unet model:="$stack" unet_backend:="$BACKEND")
  root=("${ROOT[@]}")
  [ "$stack" = ground_truth ] && args=(perception:=ground_truth) && root=()
  [ "$stack" = depth ] && args=(stack:=depth) && root=()
  sim_time=false
  if [ "$stack" = gap_nav ]; then  # a registered stack on simulated time (issue #55)
    args=(stack:="$stack") && root=() && sim_time=true
  fi
  log "$(basename "$EXP" .yaml): $stack stack, $n layouts"
  start_master
  # simulated time once for the master, before any worker's stack starts (its nodes read /use_sim_time)
  CLOCK_PID=""
  if [ "$sim_time" = true ]; then
    roslaunch --wait "$REPO/launch/sim_time.launch" >/dev/null 2>&1 &
    CLOCK_PID=$!
    until [ "$(rosparam get /use_sim_time 2>/dev/null)" = true ]; do sleep 0.5; done
  fi
  start_workers 2 "${args[@]}" planner_config:="$CFG"
  /usr/bin/python3 -m asg_agent.cli.baseline run "$EXP" --stack "$stack" --layouts "$n" --workers 2 "${root[@]}"
  stop_workers
  [ -z "$CLOCK_PID" ] || { kill "$CLOCK_PID" 2>/dev/null; wait "$CLOCK_PID" 2>/dev/null || true; }
  stop_master
done
/usr/bin/python3 -m asg_agent.cli.baseline summary "$EXP" "${ROOT[@]}" "${GT_ROOT[@]}"
