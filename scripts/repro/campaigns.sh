#!/usr/bin/env bash
# Issue #11's campaigns, back to back, resumable: for each line of the plan, run the campaign (or
# resume it where it stopped; a finished one returns at once), then export it to
# results/campaigns/NAME.jsonl.gz. Stop it at any moment (Ctrl-C, kill); run it again to go on.
#   bash scripts/repro/campaigns.sh [PLAN=results/campaign_plan.txt] [ONLY=regex on names]
#   ASG_DRY=1 bash scripts/repro/campaigns.sh     # only list what would run
#   ASG_PARK=1 bash scripts/repro/campaigns.sh    # park the unfinished ones (to commit; see below)
#   ASG_EXPORTS=results/comparison bash scripts/repro/campaigns.sh results/comparison/plan.txt
#                                           # exports (and parked stores) in another folder
# A campaign whose committed export is finished at its budget is skipped, also on a fresh clone
# without the store. A campaign resumes only from its store rows and checkpoint, which a fresh
# clone lacks: ASG_PARK=1 packs each unfinished one into results/parked/NAME.tar.xz (a few MB, to
# commit), and the next run here or on another clone unparks it first and goes on from there.
# On a 2-core machine, per 1,000 scenarios, every scenario attributed: about 25-30 minutes for
# Exp. 1 and 40-45 for Exp. 2-4 (docs/experiments.md, Table 2 wall times).
source "$(dirname "${BASH_SOURCE[0]}")/../common.sh"
PLAN="${1:-$REPO/results/campaign_plan.txt}"
ONLY="${2:-.}"
EXPORTS="$REPO/${ASG_EXPORTS:-results/campaigns}"
STORE_DEFAULT="$EXPORTS/campaigns.sqlite"
[ -z "${ASG_EXPORTS:-}" ] && STORE_DEFAULT="$REPO/results/campaigns/exp11.sqlite"
PARKED="$EXPORTS/parked"
[ -z "${ASG_EXPORTS:-}" ] && PARKED="$REPO/results/parked"
[ -f "$PLAN" ] || { echo "campaigns.sh: no plan file $PLAN" >&2; exit 2; }
if [ -z "${ASG_DRY:-}" ]; then
  install_packages
  build_workspace ON
fi
analysis() { /usr/bin/python3 -m asg_agent.analysis "$@"; }
while read -r name scenarios launch args; do
  [[ -z "$name" || "$name" == \#* ]] && continue
  [[ "$name" =~ $ONLY ]] || continue
  store="$STORE_DEFAULT"
  largs=()
  for a in $args; do
    case "$a" in
      store:=*) store="$REPO/${a#store:=}" ;;
      experiment:=*) largs+=("experiment:=$REPO/${a#experiment:=}") ;;
      planner_config:=*)  # a file name: one of asg_planner/config
        p="${a#planner_config:=}"
        [[ "$p" == */* ]] || p="$WS/src/asg_planner/config/$p"
        largs+=("planner_config:=$p") ;;
      *) largs+=("$a") ;;
    esac
  done
  export_file="$EXPORTS/$name.jsonl.gz"
  if [ -n "${ASG_PARK:-}" ]; then
    [ -f "$store" ] && analysis park --unfinished-only "$store" "$name" "$PARKED/$name.tar.xz"
    continue
  fi
  if [ ! -f "$PARKED/$name.tar.xz" ] && [ -z "${ASG_DRY:-}" ] && analysis complete "$export_file" "$scenarios"; then
    log "campaign $name: finished at $scenarios scenarios (export $export_file); skipped"
    continue
  fi
  log "campaign $name: $scenarios scenarios ($launch.launch ${largs[*]}; store $store)"
  [ -n "${ASG_DRY:-}" ] && continue  # ASG_DRY=1: list what would run
  [ -f "$PARKED/$name.tar.xz" ] && analysis unpark "$store" "$PARKED/$name.tar.xz"
  ASG_LAUNCH="$launch" ASG_STORE="$store" bash "$REPO/scripts/train.sh" "$scenarios" name:="$name" \
      resume:=true "${largs[@]}" < /dev/null
  analysis export "$store" "$name" "$export_file"
  # Finished: the export is the record, the parked copy is spent.
  if analysis complete "$export_file" "$scenarios"; then rm -f "$PARKED/$name.tar.xz"; fi
done < "$PLAN"
