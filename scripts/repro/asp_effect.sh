#!/usr/bin/env bash
# What the action saturation penalty does (docs/agent.md, "The action saturation penalty"):
# TD3-PER with and without it, on the in-process stand-in simulator (no ROS master, no workers),
# the fraction of action coordinates at the edge of their range per 100 scenarios. Writes
# results/asp_effect.json and docs/images/asp_effect.png. The measurement lives with the stand-in,
# beside the agent's tests (catkin_ws/src/asg_agent/test/stand_in/asp_effect.py).
#   bash scripts/repro/asp_effect.sh [SCENARIOS=1000] [SEEDS=3]
source "$(dirname "${BASH_SOURCE[0]}")/../common.sh"
build_workspace ON
PYTHONPATH="$WS/src/asg_agent/test${PYTHONPATH:+:$PYTHONPATH}" /usr/bin/python3 -m stand_in.asp_effect \
    --scenarios "${1:-1000}" --seeds "${2:-3}" \
    --json "$REPO/results/asp_effect.json" --out "$REPO/docs/images/asp_effect.png"
