#!/usr/bin/env bash
# The shipped models' shadow false-obstacle figures over several held-apart 600-frame sets: the
# spread quoted in docs/perception.md. The logic is asg_perception.spread (tests: test_spread.py).
#   bash scripts/repro/perception_spread.sh [SEED ...]     (default: 3 4 5 6 7 8)
#   ASG_MODEL_SUFFIX=_lite bash scripts/repro/perception_spread.sh   # the lite pair, into .../lite/
source "$(dirname "${BASH_SOURCE[0]}")/../common.sh"
source_ros
seeds=("$@")
[ $# -gt 0 ] || seeds=(3 4 5 6 7 8)
exec /usr/bin/python3 -m asg_perception.spread --seeds "${seeds[@]}" --suffix "${ASG_MODEL_SUFFIX:-}"
