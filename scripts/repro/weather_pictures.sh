#!/usr/bin/env bash
# The weather pictures of docs/simulator.md (issue #27): scenarios/shadows.yaml clear, in fog
# (40 m visibility), overcast (cloud cover 1) and both, from one camera pose; camera RGB above,
# labels below. The logic is asg_analysis.studies.pictures (tests: test_pictures.py).
#   bash scripts/repro/weather_pictures.sh [OUT=docs/images/weather_panel.png]
source "$(dirname "${BASH_SOURCE[0]}")/../common.sh"
source_ros
exec /usr/bin/python3 -m asg_analysis pictures weather --out "${1:-$REPO/docs/images/weather_panel.png}"
