#!/usr/bin/env bash
# Reproduces the shipped U-Net models (catkin_ws/src/asg_perception/models/{full,flawed}.pt) and
# their figures in docs/perception.md: renders the datasets with the simulator's ground-truth
# labeler, trains both models (in parallel, one core each) and evaluates them on a held-apart
# set. About 15 minutes on 2 cores (REFERENCE.md recipe: whole frames, 4 epochs, Adam 1e-4, batch 16).
#   bash scripts/repro/make_models.sh [WORK_DIR] [EPOCHS] [WIDTH=1.0] [SUFFIX] [LR=0.0001]
# WIDTH scales the U-Net's channels (asg_perception.model.unet); the lite pair (issue #24) is
#   bash scripts/repro/make_models.sh runs/models 8 0.5 _lite 0.001   # -> models/{full,flawed}_lite.pt
# (the datasets are shared: a second call renders nothing).
# ASG_DATASET_OPTIONS: more asg_sim_dataset options for the training and held-apart sets, which
# then live in folders named with SUFFIX (issue #27's pair, terrain and weather in half the scenes):
#   ASG_DATASET_OPTIONS="--terrain 0.5 --weather 0.5" bash scripts/repro/make_models.sh runs/models 4 1.0 _tw
source "$(dirname "${BASH_SOURCE[0]}")/../common.sh"
WORK="$(realpath -m "${1:-$REPO/runs/models}")"
EPOCHS="${2:-4}"
WIDTH="${3:-1.0}"
SUFFIX="${4:-}"
LR="${5:-0.0001}"
install_packages
build_workspace ON
export LP_NUM_THREADS=1
DATASET="$(catkin_find --first-only --libexec asg_sim asg_sim_dataset)"  # catkin's workspace search
mkdir -p "$WORK"
read -r -a OPTS <<< "${ASG_DATASET_OPTIONS:-}"
D=""  # dataset folder suffix: the plain sets are shared by every pair trained without options
[ ${#OPTS[@]} -eq 0 ] || D="$SUFFIX"
log "datasets in $WORK (seeded: the same files every time)"
[ -f "$WORK/full$D/manifest.csv" ] || "$DATASET" --out "$WORK/full$D" --count 4000 --seed 1 "${OPTS[@]}"
[ -f "$WORK/flawed$D/manifest.csv" ] || "$DATASET" --out "$WORK/flawed$D" --count 4000 --seed 2 --meshes barberry "${OPTS[@]}"
[ -f "$WORK/test$D/manifest.csv" ] || "$DATASET" --out "$WORK/test$D" --count 600 --seed 3 "${OPTS[@]}"
log "training full$SUFFIX (bushes and trees) and flawed$SUFFIX (bushes only), width $WIDTH, $EPOCHS epochs each"
for m in full flawed; do
  rosrun asg_perception train_unet --data "$WORK/$m$D" --out "$WORK/train_$m$SUFFIX" --epochs "$EPOCHS" \
    --threads 1 --seed 0 --width "$WIDTH" --lr "$LR" --resume > "$WORK/train_$m$SUFFIX.log" 2>&1 &
done
wait
grep -h "^epoch [0-9]*:" "$WORK"/train_*"$SUFFIX".log || true
MODELS="$WS/src/asg_perception/models"
cp "$WORK/train_full$SUFFIX/model.pt" "$MODELS/full$SUFFIX.pt"
cp "$WORK/train_flawed$SUFFIX/model.pt" "$MODELS/flawed$SUFFIX.pt"
log "evaluating on the held-apart set"
rosrun asg_perception evaluate_unet --data "$WORK/test$D" "full$SUFFIX=$MODELS/full$SUFFIX.pt" \
  "flawed$SUFFIX=$MODELS/flawed$SUFFIX.pt" --json "$WORK/evaluation$SUFFIX.json" --panels "$WORK/panels$SUFFIX.png"
log "models in $MODELS; figures in $WORK/evaluation.json, examples in $WORK/panels.png"
