#!/usr/bin/env bash
# Issue #36's throughput comparison, fixed before its data: round 3's configuration (bf16 `flawed`,
# 2 workers under test, 2 ground-truth reference workers re-running every scenario) against
# three-stack attribution (bf16 `flawed`, 3 workers under test, 1 `full` and 1 ground-truth
# reference worker re-running the candidates only), REPEATS campaigns of SCENARIOS each, taken in
# turn (today, three, today, three, ...) so that both see the same machine; medians compared.
#   bash scripts/repro/bench_attribution.sh [SCENARIOS=120] [REPEATS=3] [TAG=r4]
# JSON per campaign: results/bench/TAG-today-K-w2.json, TAG-three-K-w3.json; the table at the end.
set -euo pipefail
HERE="$(dirname "${BASH_SOURCE[0]}")"
SCENARIOS="${1:-120}"
REPEATS="${2:-3}"
TAG="${3:-r4}"
files=()
for k in $(seq "$REPEATS"); do
  BENCH_ATTRIBUTION=true BENCH_EXPERIMENT=exp1-bf16 bash "$HERE/bench.sh" "$SCENARIOS" "$TAG-today-$k" 2
  files+=("results/bench/$TAG-today-$k-w2.json")
  BENCH_ATTRIBUTION=three BENCH_EXPERIMENT=exp1-bf16 bash "$HERE/bench.sh" "$SCENARIOS" "$TAG-three-$k" 3
  files+=("results/bench/$TAG-three-$k-w3.json")
done
source "$HERE/../common.sh"
source_ros
/usr/bin/python3 -m asg_analysis bench table "${files[@]}"
