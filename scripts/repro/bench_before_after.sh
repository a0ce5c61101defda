#!/usr/bin/env bash
# Issue #38's bench: the same seeded TD3-PER-ASP campaign (SCENARIOS scenarios, 2 workers, seed 0,
# no attribution) on the code at BEFORE (a commit; built in a git worktree under runs/) and on this
# tree, REPEATS times each, alternated before, after, after, before, before, after, ... so that a
# drifting load falls on both; one JSON stage report per campaign in results/bench/, the table
# (python3 -m asg_analysis.bench table) at the end. EXPERIMENT is a file of this tree: the
# default, experiments/exp1-gt.yaml, leaves the U-Net out (ground-truth labels), so the figures
# are those of the worker, planner, run loop and agent, which the refactor changed.
#   bash scripts/repro/bench_before_after.sh BEFORE [SCENARIOS=120] [REPEATS=3] [TAG=r4-arch] [EXPERIMENT]
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../common.sh"
BEFORE="${1:?usage: bench_before_after.sh BEFORE [SCENARIOS] [REPEATS] [TAG] [EXPERIMENT]}"
SCENARIOS="${2:-120}"
REPEATS="${3:-3}"
TAG="${4:-r4-arch}"
EXPF="$(realpath "${5:-$REPO/experiments/exp1-gt.yaml}")"
PERCEPTION="$(/usr/bin/python3 -c "import yaml, sys; print(yaml.safe_load(open(sys.argv[1])).get('perception', 'unet'))" "$EXPF")"
# BENCH_BEFORE_TREE: a checkout of BEFORE to use (its workspace is built if it is not)
WT="${BENCH_BEFORE_TREE:-$REPO/runs/bench_before/$(git -C "$REPO" rev-parse --short "$BEFORE")}"
[ -d "$WT" ] || git -C "$REPO" worktree add -f "$WT" "$BEFORE"
[ "$(git -C "$WT" rev-parse HEAD)" = "$(git -C "$REPO" rev-parse "$BEFORE")" ] || {
  echo "bench_before_after: $WT is not a checkout of $BEFORE" >&2
  exit 2
}
OUT="$REPO/results/bench"
mkdir -p "$OUT" "$REPO/runs/bench_before/logs"
files=()
for k in $(seq "$REPEATS"); do
  order="before after"; [ $((k % 2)) -eq 0 ] && order="after before"
  for side in $order; do
    root="$REPO"; [ "$side" = before ] && root="$WT"
    store="$(mktemp -u "$REPO/runs/bench_before/store-XXXXXX.sqlite")"
    log "$TAG $side $k: $SCENARIOS scenarios of $(basename "$EXPF") on $root"
    ASG_TRAIN_PORT="${ASG_BENCH_PORT:-11397}" ASG_STORE="$store" bash "$root/scripts/train.sh" "$SCENARIOS" \
        workers:=2 name:=bench seed:=0 experiment:="$EXPF" perception:="$PERCEPTION" attribution:=false \
        extra:="--bc-weight 1.0 --no-progress --stage-report $OUT/$TAG-$side-$k.json --label $TAG-$side-$k" \
        > "$REPO/runs/bench_before/logs/$TAG-$side-$k.log" 2>&1
    # what the campaign found, every scenario's request, outcome and trajectory: equal on both
    # sides when the refactor changed no result (store.content_digest without the row numbers)
    (source_ros; /usr/bin/python3 -c "import hashlib, sys; from asg_agent.records.store import Store
rows = [r[:3] + r[4:] for r in Store(sys.argv[1], create=False).content_digest('bench')]
print(len(rows), hashlib.sha256(repr(rows).encode()).hexdigest())" "$store") > "$OUT/$TAG-$side-$k.digest"
    rm -f "$store" "${store%.sqlite}".*.ckpt
    files+=("$OUT/$TAG-$side-$k.json")
  done
done
source_ros
/usr/bin/python3 -m asg_analysis.bench table "${files[@]}"
/usr/bin/python3 -m asg_analysis.bench before-after "${files[@]}"
echo "scenarios and digest of each campaign's results:"
for f in "${files[@]}"; do echo "  $(basename "${f%.json}"): $(cat "${f%.json}.digest")"; done
