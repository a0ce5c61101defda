#!/usr/bin/env bash
# Issue #11's campaigns, back to back, resumable: for each line of the plan, run the campaign (or
# resume it where it stopped; a finished one returns at once), then export it to
# results/campaigns/NAME.jsonl.gz. Stop it at any moment (Ctrl-C, kill); run it again to go on.
#   bash scripts/campaigns.sh [PLAN=results/campaign_plan.txt] [ONLY=regex on names]
#   ASG_DRY=1 bash scripts/campaigns.sh     # only list what would run
# About 45 minutes per 1,000 Exp. 1 scenarios on a 2-core machine, 75 for Exp. 2-4.
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
PLAN="${1:-$REPO/results/campaign_plan.txt}"
ONLY="${2:-.}"
STORE_DEFAULT="$REPO/results/campaigns/exp11.sqlite"
[ -f "$PLAN" ] || { echo "campaigns.sh: no plan file $PLAN" >&2; exit 2; }
if [ -z "${ASG_DRY:-}" ]; then
  install_packages
  build_workspace ON
fi
while read -r name scenarios launch args; do
  [[ -z "$name" || "$name" == \#* ]] && continue
  [[ "$name" =~ $ONLY ]] || continue
  store="$STORE_DEFAULT"
  largs=()
  for a in $args; do
    case "$a" in
      store:=*) store="$REPO/${a#store:=}" ;;
      experiment:=*) largs+=("experiment:=$REPO/${a#experiment:=}") ;;
      *) largs+=("$a") ;;
    esac
  done
  log "campaign $name: $scenarios scenarios ($launch.launch ${largs[*]}; store $store)"
  [ -n "${ASG_DRY:-}" ] && continue  # ASG_DRY=1: list what would run
  ASG_LAUNCH="$launch" ASG_STORE="$store" bash "$REPO/scripts/train.sh" "$scenarios" name:="$name" \
      resume:=true "${largs[@]}" < /dev/null
  /usr/bin/python3 -m asg_agent.analysis export "$store" "$name" "$REPO/results/campaigns/$name.jsonl.gz"
done < "$PLAN"
