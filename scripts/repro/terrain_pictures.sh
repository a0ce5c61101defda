#!/usr/bin/env bash
# The terrain pictures of docs/simulator.md (issue #27): scenarios/exp6.yaml from (22, 50) looking
# east-north-east (yaw 0.3 rad), flat, hilly, hilly in fog and hilly overcast; camera RGB above,
# labels below, and the top-down views. The logic is asg_analysis.studies.pictures (tests: test_pictures.py).
#   bash scripts/repro/terrain_pictures.sh [OUT=docs/images/terrain_panel.png] [X=22 Y=50 YAW=0.3]
source "$(dirname "${BASH_SOURCE[0]}")/../common.sh"
source_ros
exec /usr/bin/python3 -m asg_analysis pictures terrain --out "${1:-$REPO/docs/images/terrain_panel.png}" \
    --pose "${2:-22}" "${3:-50}" "${4:-0.3}"
