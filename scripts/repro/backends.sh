#!/usr/bin/env bash
# Issue #24's backend table (docs/benchmarks.md): the U-Net on torch (eager, channels_last, bf16),
# ONNX Runtime (fp32, int8) and OpenVINO (fp32, bf16), side by side in one run on one core, for
# the shipped flawed model and its lite version, on held-apart frames (dataset seed 3).
#   bash scripts/repro/backends.sh [FRAMES=50] [REPEATS=5]
# Writes results/perception/runtimes_MODEL.json. Run it on an otherwise idle machine.
source "$(dirname "${BASH_SOURCE[0]}")/../common.sh"
FRAMES="${1:-50}"
REPEATS="${2:-5}"
install_packages
build_workspace ON
DATA="$REPO/runs/models/test"
[ -f "$DATA/manifest.csv" ] || LP_NUM_THREADS=1 rosrun asg_sim asg_sim_dataset --out "$DATA" --count 600 --seed 3 >/dev/null
mkdir -p "$REPO/results/perception"
for m in flawed flawed_lite; do
  log "$m: every backend, $FRAMES frames, $REPEATS passes (one core)"
  taskset -c 0 /usr/bin/python3 -m asg_perception.runtimes "$WS/src/asg_perception/models/$m.pt" --data "$DATA" \
      --frames "$FRAMES" --repeats "$REPEATS" --json "$REPO/results/perception/runtimes_$m.json" 2>/dev/null
done
