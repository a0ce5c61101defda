#!/usr/bin/env bash
# Issue #38's bench: the same seeded TD3-PER-ASP campaign (SCENARIOS scenarios, 2 workers, seed 0,
# no attribution) on the code at BEFORE (a commit; built in a git worktree under runs/) and on this
# tree, REPEATS times each, alternated before, after, after, before, before, after, ... so that a
# drifting load falls on both; one JSON stage report per campaign in results/bench/, the table
# (python3 -m asg_analysis bench table) at the end. EXPERIMENT is a file of this tree: the
# default, experiments/exp1-gt.yaml, leaves the U-Net out (ground-truth labels), so the figures
# are those of the worker, planner, run loop and agent, which the refactor changed.
#   bash scripts/repro/bench_before_after.sh BEFORE [SCENARIOS=120] [REPEATS=3] [TAG=r4-arch] [EXPERIMENT]
# Knobs (environment), for other benches of the same shape:
#   BENCH_WORKERS (2), BENCH_ATTRIBUTION (false; three: the full and ground-truth references re-run
#   the candidates), BENCH_ARGS_BEFORE / BENCH_ARGS_AFTER (more launch arguments of one side, e.g.
#   unet_backend:=channels_last for a tree whose default was bf16), BENCH_FAST_ARGS (set: a third
#   side, "fast", on this tree with these arguments, e.g. unet_backend:=bf16; its results differ),
#   BENCH_FAST_EXPERIMENT (the fast side's experiment file; default EXPERIMENT), BENCH_AFTER_EXPERIMENT
#   (the after side's; default EXPERIMENT), BENCH_BEFORE_TREE (a checkout of BEFORE to use; this
#   tree itself, with BEFORE=HEAD, compares two experiments on one tree). Every side is told
#   method:=td3-per-asp, whatever train.launch's default generator is (issue #54 changed it).
# Issue #53's bench (fp32 channels_last before and after it, three-stack attribution, bf16 beside;
# before it the default was bf16, so that side is told channels_last):
#   BENCH_WORKERS=3 BENCH_ATTRIBUTION=three BENCH_ARGS_BEFORE=unet_backend:=channels_last \
#     BENCH_FAST_ARGS=unet_backend:=bf16 BENCH_FAST_EXPERIMENT=experiments/exp1-bf16.yaml \
#     bash scripts/repro/bench_before_after.sh b51ff09^ 120 3 r5-numerics experiments/exp1-channels-last.yaml
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
  [ -n "${BENCH_FAST_ARGS:-}" ] && order="$order fast"
  for side in $order; do
    root="$REPO"; [ "$side" = before ] && root="$WT"
    exp="$EXPF"; [ "$side" = fast ] && exp="$(realpath "${BENCH_FAST_EXPERIMENT:-$EXPF}")"
    [ "$side" = after ] && exp="$(realpath "${BENCH_AFTER_EXPERIMENT:-$EXPF}")"
    case "$side" in
      before) read -ra more <<< "${BENCH_ARGS_BEFORE:-}" ;;
      after) read -ra more <<< "${BENCH_ARGS_AFTER:-}" ;;
      fast) read -ra more <<< "${BENCH_FAST_ARGS}" ;;
    esac
    store="$(mktemp -u "$REPO/runs/bench_before/store-XXXXXX.sqlite")"
    log "$TAG $side $k: $SCENARIOS scenarios of $(basename "$exp") on $root ${more[*]}"
    ASG_TRAIN_PORT="${ASG_BENCH_PORT:-11397}" ASG_STORE="$store" bash "$root/scripts/train.sh" "$SCENARIOS" \
        workers:="${BENCH_WORKERS:-2}" name:=bench seed:=0 method:=td3-per-asp experiment:="$exp" perception:="$PERCEPTION" \
        attribution:="${BENCH_ATTRIBUTION:-false}" "${more[@]}" \
        extra:="--bc-weight 1.0 --no-progress --stage-report $OUT/$TAG-$side-$k.json --label $TAG-$side-$k" \
        > "$REPO/runs/bench_before/logs/$TAG-$side-$k.log" 2>&1
    # what the campaign found, every scenario's request, outcome and trajectory: equal on both
    # sides when the refactor changed no result (store.content_digest without the row numbers, and
    # without the request's name, which is the experiment's: two experiment files compared by
    # BENCH_AFTER_EXPERIMENT differ in it and in nothing that runs)
    (source_ros; /usr/bin/python3 -c "import hashlib, json, sys; from asg_agent.records.store import Store
def unnamed(r):
    q = json.loads(r[4]); q.pop('name', None); return r[:3] + (json.dumps(q, sort_keys=True),) + r[5:]
rows = [unnamed(r) for r in Store(sys.argv[1], create=False).content_digest('bench')]
print(len(rows), hashlib.sha256(repr(rows).encode()).hexdigest())" "$store") > "$OUT/$TAG-$side-$k.digest"
    rm -f "$store" "${store%.sqlite}".*.ckpt
    files+=("$OUT/$TAG-$side-$k.json")
  done
done
source_ros
/usr/bin/python3 -m asg_analysis bench table "${files[@]}"
/usr/bin/python3 -m asg_analysis bench before-after $(printf '%s\n' "${files[@]}" | grep -v -- "-fast-")
echo "scenarios and digest of each campaign's results:"
for f in "${files[@]}"; do echo "  $(basename "${f%.json}"): $(cat "${f%.json}.digest")"; done
