#!/usr/bin/env bash
# Soak (issue #14): a long campaign with 2 workers (flawed U-Net) while scene workers, stack nodes
# and the agent itself are killed with SIGKILL at random moments. The workers respawn (worker.launch);
# the agent is restarted with --resume. The soak lasts HOURS: at the end the killer stops, the agent
# is killed a last time and resumed with its budget cut to the scenarios it has begun, so the
# campaign drains and finishes. Then every scenario 0..N-1 must be stored exactly once.
# Writes results/reliability/soak.json (scenarios, kills by kind, retries, lost, duplicates) and
# prints it; docs/reliability.md quotes the last result.
#   [SOAK_EXTRA="--bc-weight 1.0"] bash scripts/repro/soak.sh [HOURS=2] [MIN_GAP_S=60] [MAX_GAP_S=240] \
#       [METHOD=random] [SEED=1] [EXP=exp1]        (SOAK_EXTRA: more campaign options)
# The campaign is a valid campaign of METHOD on experiments/EXP.yaml (kills change nothing in what is stored), so
# its export can serve as a search-comparison arm (docs/experiments.md).
# SOAK_REFERENCE=2: attribution on, every scenario also run on 2 reference workers (ground-truth
# stack, worker_2 and worker_3), which the killer hits too (their scene workers and planners).
# SOAK_REFERENCE=three: three-stack attribution (issue #36): worker_2 runs the unflawed U-Net
# (`full`), worker_3 ground truth, and the candidates are re-run on both; the killer hits them too.
source "$(dirname "${BASH_SOURCE[0]}")/../common.sh"
HOURS="${1:-2}"
MIN_GAP="${2:-60}"
MAX_GAP="${3:-240}"
METHOD="${4:-random}"
SEED="${5:-1}"
EXP="${6:-exp1}"
BIG=1000000  # the budget while the kills go on: the clock, not the count, ends the first leg
install_packages
build_workspace ON
use_local_master "${ASG_SOAK_PORT:-11395}" "$REPO/runs/soak/logs"
OUT="$REPO/results/reliability"
STORE="${ASG_STORE:-$REPO/results/reliability/soak.sqlite}"
NAME="soak-$EXP-$METHOD-s$SEED"
KILLS="$REPO/runs/soak/kills.log"
mkdir -p "$OUT"
: > "$KILLS"
: > "$REPO/runs/soak/agent.log"
start_master
REF="${SOAK_REFERENCE:-0}"
start_workers 2 perception:=unet
UNDER_TEST=("${WORKER_PIDS[@]}")
REF_ARGS=()
NOSEG=2  # the first worker without a segmenter
if [ "$REF" = three ]; then
  roslaunch "$REPO/launch/worker.launch" ns:=worker_2 markers:=false perception:=unet model:=full >/dev/null 2>&1 &
  UNDER_TEST+=($!)
  roslaunch "$REPO/launch/worker.launch" ns:=worker_3 markers:=false perception:=ground_truth >/dev/null 2>&1 &
  UNDER_TEST+=($!)
  REF=2
  NOSEG=3
  REF_ARGS=(--reference full=1 --reference ground_truth=1)
elif [ "$REF" -gt 0 ]; then
  for ((w = 2; w < 2 + REF; w++)); do
    roslaunch "$REPO/launch/worker.launch" ns:="worker_$w" markers:=false perception:=ground_truth >/dev/null 2>&1 &
    UNDER_TEST+=($!)
  done
  REF_ARGS=(--reference-workers "$REF")
fi
WORKER_PIDS=("${UNDER_TEST[@]}")
killer=""
cleanup() { if [ -n "$killer" ]; then kill "$killer" 2>/dev/null || true; fi; stop_workers; stop_master; }
trap cleanup EXIT
# The killer: every MIN_GAP..MAX_GAP seconds one victim, by kind in turn of a random draw.
(
  while sleep "$(( MIN_GAP + RANDOM % (MAX_GAP - MIN_GAP + 1) ))"; do
    w=$(( RANDOM % (2 + REF) ))
    kind=$(( RANDOM % 4 ))
    if [ "$w" -ge "$NOSEG" ] && [ "$kind" = 2 ]; then kind=$(( RANDOM % 2 )); fi  # no segmenter on a ground-truth worker
    case $kind in
      0) victim="/worker_$w/scene_worker" ;;
      1) victim="/worker_$w/planner" ;;
      2) victim="/worker_$w/segmenter" ;;
      3) victim="agent" ;;
    esac
    if [ "$victim" = agent ]; then
      pid=$(pgrep -f "asg_agent.cli.campaign .*--name $NAME" | head -1)
    else
      pid=$(/usr/bin/python3 -c "import rosgraph, xmlrpc.client, sys
try:
    print(xmlrpc.client.ServerProxy(rosgraph.Master('/soak').lookupNode('$victim')).getPid('/soak')[2])
except Exception:
    pass")
    fi
    [ -n "$pid" ] && kill -9 "$pid" 2>/dev/null && echo "$(date +%s) $victim $pid" >> "$KILLS"
  done
) & killer=$!
start=$(date +%s)
deadline=$(( start + $(/usr/bin/python3 -c "print(int(float('$HOURS') * 3600))") ))
agent() {  # agent BUDGET [--resume]
  /usr/bin/python3 -m asg_agent.cli.campaign "$REPO/experiments/$EXP.yaml" --workers 2 --method "$METHOD" \
      --seed "$SEED" --scenarios "$1" --store "$STORE" --name "$NAME" --no-progress "${REF_ARGS[@]}" ${SOAK_EXTRA:-} "${@:2}" \
      >> "$REPO/runs/soak/agent.log" 2>&1
}
resume=()
/usr/bin/python3 -c "import sys; from asg_agent.campaign.store import Store; sys.exit(Store('$STORE').campaign('$NAME') is None)" \
    2>/dev/null && resume=(--resume)
# Leg 1: kills until the deadline; the agent is restarted with --resume whenever it dies.
while [ "$(date +%s)" -lt "$deadline" ]; do
  agent "$BIG" "${resume[@]}" & apid=$!
  while kill -0 "$apid" 2>/dev/null && [ "$(date +%s)" -lt "$deadline" ]; do sleep 2; done
  if kill -0 "$apid" 2>/dev/null; then
    kill "$killer" 2>/dev/null || true
    pkill -9 -f "asg_agent.cli.campaign .*--name $NAME" && echo "$(date +%s) agent-final $apid" >> "$KILLS"
  fi
  wait "$apid" 2>/dev/null || true
  echo "$(date +%s) agent exited: restarting with --resume" >> "$REPO/runs/soak/agent.log"
  resume=(--resume)
  sleep 1
done
kill "$killer" 2>/dev/null || true
# Leg 2: no more kills; the budget is cut to the scenarios begun, and the campaign drains.
N=$(/usr/bin/python3 -c "from asg_agent.campaign.store import Store; print(max(Store('$STORE').jobs('$NAME')) + 1)")
echo "$(date +%s) draining: budget cut to $N scenarios" >> "$REPO/runs/soak/agent.log"
until agent "$N" --resume; do sleep 1; done
end=$(date +%s)
kill "$killer" 2>/dev/null || true
/usr/bin/python3 "$REPO/scripts/repro/soak_report.py" "$STORE" "$NAME" "$N" "$KILLS" "$REPO/runs/soak/agent.log" \
    "$start" "$end" "$OUT/soak.json"
