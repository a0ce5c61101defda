#!/usr/bin/env bash
# Issue #68 item 10: the design loop's per-pixel figures on `heldout-findings` without its near
# twins (scenes a training source holds within the augmentation's radius; docs/design-loop.md,
# "Near twins"). The committed evaluation files pool the frames, so the set is rendered again as
# it was built (the same export, classes, frame count, seed and training sources, at the
# same-layout tolerance it was built at), and every arm of both rounds is evaluated on all of its
# frames and on those of the scenes that are not twins (asg_analysis.studies.held_apart finds them).
# Writes results/hardening/twins/ and the page's twins block. About 15 minutes on 2 cores.
#   bash scripts/repro/heldout_twins.sh [WORK=runs/twins]
source "$(dirname "${BASH_SOURCE[0]}")/../common.sh"
WORK="${1:-runs/twins}"
OUT=results/hardening/twins
install_packages
build_workspace ON
export LP_NUM_THREADS=1
cd "$REPO"  # relative paths: the records hold no machine's paths
MODELS=catkin_ws/src/asg_perception/models
made=results/hardening/heldout-findings.json
field() { /usr/bin/python3 -c "import json,sys; print(json.load(open(sys.argv[1]))$1)" "$made"; }
mkdir -p "$WORK" "$OUT"
log "heldout-findings rendered again as built: $(field "['frames']") frames, seed $(field "['seed']")"
[ -f "$WORK/heldout-findings/frames/manifest.csv" ] ||
  /usr/bin/python3 -m asg_agent.cli.harden frames --export "$(field "['made_from']['export']")" \
    --classes "$(field "['made_from']['classes'][0]"),$(field "['made_from']['classes'][1]")" \
    --out "$WORK/heldout-findings" --frames "$(field "['frames']")" --seed "$(field "['seed']")" \
    --apart-from "$(field "['made_from']['apart_from']")" --drop-shared --tol-m 0.01
cp "$WORK/heldout-findings/hardening.json" "$OUT/heldout-findings.json"
/usr/bin/python3 -m asg_analysis held-apart --frames-without-twins "$WORK/heldout-findings/frames" "$WORK/twins-left-out"
ARMS=("flawed=$MODELS/flawed.pt" "full=$MODELS/full.pt")
for r in 1 2; do ARMS+=("hardened-findings-$r=$MODELS/flawed_hf$r.pt" "hardened-random-$r=$MODELS/flawed_hr$r.pt"); done
for k in rerendered twins-left-out; do
  data="$WORK/heldout-findings/frames"
  [ "$k" = rerendered ] || data="$WORK/twins-left-out"
  [ -f "$OUT/evaluation-heldout-findings-$k.json" ] ||
    /usr/bin/python3 -m asg_perception.evaluate --data "$data" "${ARMS[@]}" --json "$OUT/evaluation-heldout-findings-$k.json"
done
/usr/bin/python3 -m asg_analysis held-apart --doc docs/design-loop.md
