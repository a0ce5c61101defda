#!/usr/bin/env bash
# Issue #53: the segmenter node's CPU a frame against its U-Net's alone (scripts/repro/segmenter_overhead.py),
# on a master of its own (port 11422).
#   bash scripts/repro/segmenter_overhead.sh [FRAMES=200] [ROUNDS=3]
source "$(dirname "${BASH_SOURCE[0]}")/../common.sh"
build_workspace ON
use_local_master 11422 "$REPO/runs/segmenter_overhead/logs"
trap 'stop_master' EXIT
start_master
LP_NUM_THREADS=1 /usr/bin/python3 "$REPO/scripts/repro/segmenter_overhead.py" --frames "${1:-200}" --rounds "${2:-3}"
