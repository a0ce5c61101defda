#!/usr/bin/env bash
# Issue #40, the design loop's hardening (experiments/protocol-design-loop.yaml): frames from the
# found failure scenes and, as many, from random scenes; the `flawed` U-Net fine-tuned on each with
# as many frames of its own training set beside them (rehearsal: fine-tuning on the new frames
# alone forgot the sun angles Exp. 1 never shows, results/hardening/frames-only/), same settings;
# per-pixel figures on held-apart frames; suite pass rates of every arm.
#   bash scripts/repro/harden.sh [WORK=runs/harden] [ROUND=1]
# Round 2 and later search the model of the round before first: ASG_HARDEN_FINDINGS names that
# campaign's export (and ASG_HARDEN_RANDOM a random campaign's, seeds unused so far).
# Steps whose output exists are skipped, so a stopped run continues. About an hour on 2 idle
# cores (the two trainings, one core each, take most of it). Writes the models to
# asg_perception/models/flawed_{hf,hr}ROUND.pt and to results/hardening/: evaluation-SET-ROUND.json (per-pixel figures), suite outcomes recorded
# in the suites (labels flawed-cl, full-cl, hardened-findings-ROUND, hardened-random-ROUND).
source "$(dirname "${BASH_SOURCE[0]}")/../common.sh"
WORK="$(realpath -m "${1:-$REPO/runs/harden}")"
ROUND="${2:-1}"
OUT="$REPO/results/hardening"
FINDINGS_EXPORT="${ASG_HARDEN_FINDINGS:-$REPO/results/attribution/exp1c-td3-per-asp-s0.jsonl.gz}"
RANDOM_EXPORT="${ASG_HARDEN_RANDOM:-$REPO/results/comparison/exp1b-random-s1.jsonl.gz}"
HELDOUT_EXPORT="$REPO/results/round4/round4-pilot-reward-proxy-s0.jsonl.gz"
# The held-apart sets share no scene with any arm's training source of any round (issue #57): one
# set serves every round, so it is built apart from the protocol's round 1 and round 2 sources,
# this round's, and ASG_HARDEN_APART (comma-separated exports) for later rounds.
APART="$REPO/results/attribution/exp1c-td3-per-asp-s0.jsonl.gz,$REPO/results/comparison/exp1b-random-s1.jsonl.gz"
APART="$APART,$REPO/results/hardening/loop-hf1-s20.jsonl.gz,$REPO/results/comparison/exp1b-random-s2.jsonl.gz"
APART="$APART,$FINDINGS_EXPORT,$RANDOM_EXPORT${ASG_HARDEN_APART:+,$ASG_HARDEN_APART}"
FRAMES=1664
install_packages
build_workspace ON
export LP_NUM_THREADS=1
MODELS="$WS/src/asg_perception/models"  # the hardened models ship beside flawed.pt: model:=flawed_hf1
mkdir -p "$WORK" "$OUT"
harden() { /usr/bin/python3 -m asg_agent.cli.harden frames "$@"; }

log "frame sets in $WORK"
[ -f "$WORK/findings$ROUND/frames/manifest.csv" ] ||
  harden --export "$FINDINGS_EXPORT" --classes flaw,model --out "$WORK/findings$ROUND" --frames $FRAMES --seed 0
SCENES=$(/usr/bin/python3 -c "import json,sys; print(len(json.load(open(sys.argv[1]))['sources']))" \
  "$WORK/findings$ROUND/hardening.json")
[ -f "$WORK/random$ROUND/frames/manifest.csv" ] ||
  harden --export "$RANDOM_EXPORT" --scenes "$SCENES" --out "$WORK/random$ROUND" --frames $FRAMES --seed 0
[ -f "$WORK/heldout-findings/frames/manifest.csv" ] ||
  harden --export "$HELDOUT_EXPORT" --classes flaw,model --out "$WORK/heldout-findings" --frames 848 --seed 1 \
    --apart-from "$APART" --drop-shared  # held apart from every arm's sources (issue #57)
[ -f "$WORK/test/manifest.csv" ] || rosrun asg_sim asg_sim_dataset --out "$WORK/test" --count 600 --seed 3
# the first FRAMES frames of flawed.pt's own training set (scripts/repro/make_models.sh: seed 2, barberries)
[ -f "$WORK/rehearsal/manifest.csv" ] ||
  rosrun asg_sim asg_sim_dataset --out "$WORK/rehearsal" --count $FRAMES --seed 2 --meshes barberry

log "fine-tuning flawed.pt (round 1) or each arm's model of the round before on each frame set ($FRAMES frames and $FRAMES of rehearsal, 4 epochs, Adam 1e-4, one core each)"
for arm in findings random; do
  tag=h${arm:0:1}$ROUND
  [ -f "$MODELS/flawed_$tag.pt" ] && continue
  START="$WS/src/asg_perception/models/flawed.pt"
  [ "$ROUND" = 1 ] || START="$MODELS/flawed_h${arm:0:1}$((ROUND - 1)).pt"  # each arm hardens its own
  /usr/bin/python3 -m asg_perception.train --data "$WORK/$arm$ROUND/frames,$WORK/rehearsal" --out "$WORK/train_$arm$ROUND" \
    --init "$START" --epochs 4 --lr 0.0001 --batch-size 16 --threads 1 --seed 0 --resume \
    > "$WORK/train_$arm$ROUND.log" 2>&1 &
done
wait
for arm in findings random; do
  tag=h${arm:0:1}$ROUND
  [ -f "$MODELS/flawed_$tag.pt" ] || cp "$WORK/train_$arm$ROUND/model.pt" "$MODELS/flawed_$tag.pt"
done

log "per-pixel figures on the held-apart sets"
ARMS=("flawed=$MODELS/flawed.pt" "full=$MODELS/full.pt")
for r in $(seq 1 "$ROUND"); do ARMS+=("hardened-findings-$r=$MODELS/flawed_hf$r.pt" "hardened-random-$r=$MODELS/flawed_hr$r.pt"); done
for set in test heldout-findings; do
  data="$WORK/$set"
  [ -f "$data/manifest.csv" ] || data="$WORK/$set/frames"
  [ -f "$OUT/evaluation-$set-$ROUND.json" ] ||
    /usr/bin/python3 -m asg_perception.evaluate --data "$data" "${ARMS[@]}" --json "$OUT/evaluation-$set-$ROUND.json" \
      --panels "$OUT/panels-$set-$ROUND.png"
done

log "suite pass rates (one worker a stack, U-Net in fp32 channels_last)"
[ -f "$OUT/suite-r4pilot/suite.yaml" ] ||
  /usr/bin/python3 -m asg_agent.cli.suite export "$HELDOUT_EXPORT" --out "$OUT/suite-r4pilot" --classes flaw,model \
    --apart-from "$APART" --drop-shared
[ -f "$OUT/suite-exp1c/suite.yaml" ] || cp -r "$REPO/tests/suites/exp1c-flaw" "$OUT/suite-exp1c"
STACKS=("flawed-cl=perception:=unet model:=flawed unet_backend:=channels_last"
  "full-cl=perception:=unet model:=full unet_backend:=channels_last")
for r in $(seq 1 "$ROUND"); do
  STACKS+=("hardened-findings-$r=perception:=unet model:=flawed_hf$r unet_backend:=channels_last"
    "hardened-random-$r=perception:=unet model:=flawed_hr$r unet_backend:=channels_last")
done
for suite in "$OUT/suite-exp1c" "$OUT/suite-r4pilot"; do
  todo=()
  for s in "${STACKS[@]}"; do grep -q "^    ${s%%=*}:" "$suite/suite.yaml" || todo+=("$s"); done
  [ ${#todo[@]} -eq 0 ] || bash "$REPO/scripts/repro/suite_record.sh" "$suite" "${todo[@]}"
done
/usr/bin/python3 -m asg_analysis hardening "$OUT" --json "$OUT/summary.json" --markdown
