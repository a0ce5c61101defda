#!/usr/bin/env bash
# Soak (issue #14): a long campaign while scene workers, stack nodes and the agent are killed with
# SIGKILL at random moments; then every scenario must be stored exactly once. The logic is
# asg_agent.cli.soak (its docstring; tests in test_soak.py). Writes results/reliability/soak.json
# and prints it; docs/reliability.md quotes the last result.
#   [SOAK_REFERENCE=0|N|three] [SOAK_EXTRA="--bc-weight 1.0"] bash scripts/repro/soak.sh [HOURS=2] \
#       [MIN_GAP_S=60] [MAX_GAP_S=240] [METHOD=random] [SEED=1] [EXP=exp1]
source "$(dirname "${BASH_SOURCE[0]}")/../common.sh"
install_packages
build_workspace ON
exec /usr/bin/python3 -m asg_agent.cli.soak --hours "${1:-2}" --gaps "${2:-60}" "${3:-240}" \
    --method "${4:-random}" --seed "${5:-1}" --experiment "${6:-exp1}" --reference "${SOAK_REFERENCE:-0}" \
    "--extra=${SOAK_EXTRA:-}" --store "${ASG_STORE:-$REPO/results/reliability/soak.sqlite}" \
    --port "${ASG_SOAK_PORT:-11395}"
