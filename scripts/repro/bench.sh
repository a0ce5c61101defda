#!/usr/bin/env bash
# `bench`: where a real campaign's time goes. The same seeded TD3-PER-ASP campaign on the paper's
# Exp. 1 with the flawed U-Net in the loop, run with 1 and with 2 scene workers (every result is
# applied in job order, so both runs propose the same scenarios); every node's stage timers are
# read at the start and the end. Prints scenarios an hour, simulated seconds per wall second per
# worker, the per-scenario stage breakdown, the U-Net's inference-only bound and the ratio to the
# paper's 625 an hour; keeps the JSON of each run under results/bench/TAG-wN.json.
#   bash scripts/repro/bench.sh [SCENARIOS=160] [TAG=now] [WORKER_COUNTS="1 2"]
# BENCH_BASELINE=1: the pipeline as it was before issue #13's changes (odom and tf at every tick,
# planner markers on, freed workers wait for the agent's update) - the "before" column.
# BENCH_ATTRIBUTION=true: every scenario also runs on the ground-truth reference stack (2 more
# workers). BENCH_EXPERIMENT=exp1-bf16: another experiment file (its unet_backend is passed on).
# The method is named (td3-per-asp), not train.launch's default, so the figures stay comparable
# when the default generator changes (issue #54). Run it on an otherwise idle machine: it measures
# the machine. docs/benchmarks.md.
source "$(dirname "${BASH_SOURCE[0]}")/../common.sh"
SCENARIOS="${1:-160}"
TAG="${2:-now}"
COUNTS="${3:-1 2}"
install_packages
build_workspace ON
OUT="$REPO/results/bench"
mkdir -p "$OUT"
TMP="$(mktemp -d)"
trap 'rm -rf "$TMP"' EXIT
files=()
EXPF="$REPO/experiments/${BENCH_EXPERIMENT:-exp1}.yaml"
read -r BACKEND MODEL < <(/usr/bin/python3 -c "from asg_agent.records.experiment import load_experiment; e = load_experiment('$EXPF'); print(e.unet_backend, e.model)")
BASE_ARGS=(experiment:="$EXPF" unet_backend:="$BACKEND" model:="$MODEL" attribution:="${BENCH_ATTRIBUTION:-false}")
MODEL_PATH="$MODEL"
[[ "$MODEL" == */* || "$MODEL" == *.pt ]] || MODEL_PATH="$WS/src/asg_perception/models/$MODEL.pt"
log "U-Net ($MODEL) alone on one core (FLOP a frame, ms a frame, practical peak)"
/usr/bin/python3 -m asg_perception.peak "$MODEL_PATH" --json "$OUT/$TAG-peak.json"
BASE_EXTRA=""
if [ "${BENCH_BASELINE:-0}" = 1 ]; then
  BASE_ARGS+=(odom_every_tick:=true markers:=true)
  BASE_EXTRA="--no-early-dispatch"
fi
for w in $COUNTS; do
  log "campaign: $SCENARIOS Exp. 1 scenarios, TD3-PER-ASP, flawed U-Net, $w worker(s)"
  ASG_TRAIN_PORT="${ASG_BENCH_PORT:-11397}" ASG_STORE="$TMP/bench.sqlite" bash "$REPO/scripts/train.sh" \
      "$SCENARIOS" workers:="$w" name:="bench-w$w" seed:=0 method:=td3-per-asp "${BASE_ARGS[@]}" \
      extra:="$BASE_EXTRA --bc-weight 1.0 --no-progress --stage-report $OUT/$TAG-w$w.json --label $TAG-w$w" \
      > "$TMP/w$w.log" 2>&1 || { tail -30 "$TMP/w$w.log"; echo "bench: the campaign with $w worker(s) failed" >&2; exit 1; }
  grep -E "stage report|proxy >= 3" "$TMP/w$w.log" || true
  files+=("$OUT/$TAG-w$w.json")
done
/usr/bin/python3 -m asg_analysis bench table "${files[@]}"
