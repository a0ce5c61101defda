#!/usr/bin/env bash
# The main job: a short campaign of the adversarial scene generator (TD3-PER-ASP) on the paper's
# Exp. 1 with the flawed U-Net in the loop, two scene workers on this machine. Installs what is
# missing and builds first; prints a progress bar, then the summary and where the store is.
#   bash scripts/train.sh [SCENARIOS] [extra launch args, e.g. method:=random seed:=1 resume:=true]
# Default 150 scenarios (about 8 minutes on a 2-core machine). Idempotent: a finished campaign is
# reported, an unfinished one resumed (resume:=true). ASG_LAUNCH=differential runs
# launch/differential.launch instead (2 workers under test, 2 reference workers).
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
SCENARIOS="${1:-150}"
shift || true
install_packages
build_workspace ON
# A master of our own on a port of our own, on loopback: a user's roscore is left alone.
LOG="$REPO/runs/train/logs"
use_local_master "${ASG_TRAIN_PORT:-11398}" "$LOG"
STORE="${ASG_STORE:-$REPO/results/train.sqlite}"
mkdir -p "$(dirname "$STORE")"
log "campaign: $SCENARIOS Exp. 1 scenarios, flawed U-Net, 2 workers (worker logs: $LOG)"
roslaunch -p "${ROS_MASTER_URI##*:}" "$REPO/launch/${ASG_LAUNCH:-train}.launch" scenarios:="$SCENARIOS" \
    store:="$STORE" "$@"
log "store: $STORE (docs/agent.md: schema, resume, reading it)"
