#!/usr/bin/env bash
# The main job: a short campaign of the adversarial scene generator (train.launch's default: the
# distinct-failures study's best arm, novelty-ts in Exp. 1's route-wide action space on the flaw
# reward; issue #78) on the
# paper's Exp. 1 with the flawed U-Net in the loop, two scene workers on this machine. Installs what is
# missing and builds first; prints a progress bar, then the summary (the findings, their distinct
# places and the replay command of the best), the rules its failures have in common, and where the
# store is.
#   bash scripts/train.sh [SCENARIOS] [extra launch args, e.g. method:=random seed:=1 resume:=true]
# Default 150 scenarios (minutes on a 2-core machine: docs/benchmarks.md, CPU classes). Idempotent: a finished campaign is
# reported, an unfinished one resumed (train.sh adds resume:=true; resume:=false refuses a name
# already in the store). ASG_LAUNCH=differential runs
# launch/differential.launch instead (2 workers under test, 2 reference workers).
# The workers run from the launch file in the background (their roslaunch output in the log
# folder); the campaign node runs in the foreground with the command line the launch file gives
# it (`roslaunch --args /campaign`), so its exit status is this script's and a finished campaign
# ends without roslaunch's "REQUIRED process has died" banner.
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
SCENARIOS="${1:-150}"
shift || true
# ASG_BUILT=1 (set by a plan, whose campaigns.sh did both): skip the install and build check
if [ -n "${ASG_BUILT:-}" ]; then source_ros; else install_packages; build_workspace ON; fi
# A master of our own on a port of our own, on loopback: a user's roscore is left alone.
LOG="$REPO/runs/train/logs"
use_local_master "${ASG_TRAIN_PORT:-11398}" "$LOG"
STORE="${ASG_STORE:-$REPO/results/train.sqlite}"
mkdir -p "$(dirname "$STORE")"
LAUNCH="$REPO/launch/${ASG_LAUNCH:-train}.launch"
ARGS=(scenarios:="$SCENARIOS" store:="$STORE" "$@")
# Idempotent: run again, the campaign of the same name resumes (a finished one is reported at
# once), unless the command line says resume:= itself
[[ " $* " == *" resume:="* ]] || ARGS+=(resume:=true)
if [ "${ASG_LAUNCH:-train}" = train ]; then
  # The experiment file decides the workers' stack (model, U-Net numerics, planner): the arguments
  # it implies that the command line leaves out; a contradiction is refused here (issue #53).
  IMPLIED="$(/usr/bin/python3 -m asg_agent.cli.launch_args "$@")" || exit 2
  [ -z "$IMPLIED" ] || { mapfile -t MORE <<< "$IMPLIED"; ARGS+=("${MORE[@]}"); }
fi
read -ra CAMPAIGN < <(roslaunch --args /campaign "$LAUNCH" "${ARGS[@]}")
[ "${#CAMPAIGN[@]}" -gt 1 ] || { echo "train.sh: $LAUNCH gives no campaign command line" >&2; exit 2; }
log "campaign: $SCENARIOS scenarios of $(basename "${CAMPAIGN[1]}") (worker logs: $LOG)"
roslaunch -p "${ROS_MASTER_URI##*:}" "$LAUNCH" "${ARGS[@]}" campaign:=false > "$LOG/roslaunch.log" 2>&1 &
LAUNCH_PID=$!
stop_launch() {
  kill -INT "$LAUNCH_PID" 2>/dev/null || true
  wait "$LAUNCH_PID" 2>/dev/null || true
}
trap stop_launch EXIT
for _ in $(seq 60); do rosparam get /run_id >/dev/null 2>&1 && break; sleep 0.5; done  # the master is up
rc=0
"${CAMPAIGN[@]}" || rc=$?
stop_launch
trap - EXIT
# the store the campaign wrote (store:= may name another than the default)
for i in "${!CAMPAIGN[@]}"; do [ "${CAMPAIGN[$i]}" = --store ] && STORE="${CAMPAIGN[$((i + 1))]}"; done
if [ "$rc" = 0 ]; then
  # what the campaign's failures have in common (issue #78): rules learnt from its own results
  /usr/bin/python3 -m asg_analysis rules learn --store "$STORE" || true
fi
log "store: $STORE (docs/agent.md: schema, resume, reading it)"
exit "$rc"
