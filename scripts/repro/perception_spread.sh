#!/usr/bin/env bash
# The shipped models' shadow false-obstacle figures over several held-apart 600-frame sets
# (dataset seeds other than the training seeds 1 and 2): the spread quoted in docs/perception.md.
#   bash scripts/repro/perception_spread.sh [SEED ...]     (default: 3 4 5 6 7 8)
#   ASG_MODEL_SUFFIX=_lite bash scripts/repro/perception_spread.sh   # the lite pair, into .../lite/
source "$(dirname "${BASH_SOURCE[0]}")/../common.sh"
source_ros
SEEDS=("${@:-3 4 5 6 7 8}")
[ $# -gt 0 ] || SEEDS=(3 4 5 6 7 8)
SUFFIX="${ASG_MODEL_SUFFIX:-}"
OUT="$REPO/results/perception_spread${SUFFIX:+/${SUFFIX#_}}"
mkdir -p "$OUT"
for s in "${SEEDS[@]}"; do
  d="$(mktemp -d)"
  log "seed $s: rendering 600 frames, evaluating full and flawed"
  LP_NUM_THREADS=1 "$WS/devel/lib/asg_sim/asg_sim_dataset" --out "$d" --count 600 --seed "$s" \
      --meshes juniper,barberry >/dev/null
  /usr/bin/python3 "$WS/src/asg_perception/scripts/evaluate_unet" \
      "full=$WS/src/asg_perception/models/full$SUFFIX.pt" "flawed=$WS/src/asg_perception/models/flawed$SUFFIX.pt" \
      --data "$d" --json "$OUT/seed_$s.json" >/dev/null
  rm -rf "$d"
done
/usr/bin/python3 - "$OUT" <<'PY'
import glob, json, os, statistics, sys
rows = []
for path in sorted(glob.glob(os.path.join(sys.argv[1], "seed_*.json"))):
    d = json.load(open(path))
    full, flawed = d["results"]["full"], d["results"]["flawed"]
    rows.append((os.path.basename(path)[5:-5], flawed["shadow_false_obstacle_rate"] / full["shadow_false_obstacle_rate"],
                 flawed["low_sun"]["shadow_false_obstacle_rate"] / full["low_sun"]["shadow_false_obstacle_rate"],
                 full["shadow_false_obstacle_rate"], flawed["shadow_false_obstacle_rate"]))
print("| dataset seed | full | flawed | ratio overall | ratio low sun |")
print("|---|---|---|---|---|")
for seed, r, rl, fu, fl in rows:
    print(f"| {seed} | {fu:.4f} | {fl:.4f} | {r:.1f}x | {rl:.1f}x |")
ov = [r[1] for r in rows]; lo = [r[2] for r in rows]
print(f"\noverall ratio: median {statistics.median(ov):.1f}x, min {min(ov):.1f}x, max {max(ov):.1f}x; "
      f"low sun: median {statistics.median(lo):.1f}x, min {min(lo):.1f}x, max {max(lo):.1f}x")
PY
