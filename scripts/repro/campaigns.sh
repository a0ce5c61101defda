#!/usr/bin/env bash
# A plan of campaigns, back to back, resumable (issue #11): for each line of the plan, run the
# campaign (or resume it where it stopped; a finished one returns at once), then export it to
# EXPORTS/NAME.jsonl.gz. Stop it at any moment (Ctrl-C, kill); run it again to go on. The logic is
# asg_agent.cli.plan (its docstring: the plan format, parking, paths; tests in test_plan.py).
#   bash scripts/repro/campaigns.sh [PLAN=results/campaign_plan.txt] [ONLY=regex on names]
#   ASG_DRY=1 bash scripts/repro/campaigns.sh     # only list what would run
#   ASG_PARK=1 bash scripts/repro/campaigns.sh    # park the unfinished ones (to commit)
#   ASG_EXPORTS=results/comparison bash scripts/repro/campaigns.sh results/comparison/plan.txt
#                                           # exports (and parked stores) in another folder
# On a 2-core machine, per 1,000 scenarios, every scenario attributed: about 25-30 minutes for
# Exp. 1 and 40-45 for Exp. 2-4 (docs/experiments.md, Table 2 wall times).
source "$(dirname "${BASH_SOURCE[0]}")/../common.sh"
opts=(--only "${2:-.}")
[ -n "${ASG_EXPORTS:-}" ] && opts+=(--exports "$ASG_EXPORTS")
[ -n "${ASG_PARK:-}" ] && opts+=(--park)
if [ -n "${ASG_DRY:-}" ]; then
  opts+=(--dry)
  export PYTHONPATH="$WS/src/asg_agent/src:$WS/src/asg_perception/src:$WS/src/asg_scenario/src:${PYTHONPATH:-}"
else
  install_packages
  build_workspace ON
fi
exec /usr/bin/python3 -m asg_agent.cli.plan "${1:-$REPO/results/campaign_plan.txt}" "${opts[@]}"
