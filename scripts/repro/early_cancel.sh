#!/usr/bin/env bash
# Issue #53: sound_runs' early-cancel check 20 times in a row on one worker with the flawed U-Net
# (the default numerics), first with the cancel as the test makes it now, then as it was made
# before (ASG_NAIVE=1 only: to watch actionlib's LOST come back). Own master on port 11421.
#   bash scripts/repro/early_cancel.sh [ROUNDS=20]
source "$(dirname "${BASH_SOURCE[0]}")/../common.sh"
ROUNDS="${1:-20}"
build_workspace ON
use_local_master 11421 "$REPO/runs/early_cancel/logs"
trap 'stop_workers; stop_master' EXIT
start_master
start_workers 1 perception:=unet model:=flawed command_timeout:=5.0
/usr/bin/python3 "$REPO/tests/early_cancel_loop.py" --rounds "$ROUNDS" ${ASG_NAIVE:+--naive}
