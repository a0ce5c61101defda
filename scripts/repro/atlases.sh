#!/usr/bin/env bash
# The failure atlases of the benchmark scenes (issue #93; docs/agent.md, "Failure atlas"), rebuilt
# from the exports in results/: each pools every export of its identity (scene, stack under
# test, references, kind of finding) and skips the others, saying why. A few minutes on 2 cores.
#   bash scripts/repro/atlases.sh            # writes results/atlas/*.json
# A campaign's new places: rosrun asg_agent atlas add results/atlas/NAME.json EXPORT.jsonl.gz
source "$(dirname "${BASH_SOURCE[0]}")/../common.sh"
export PYTHONPATH="$WS/src/asg_agent/src:$WS/src/asg_scenario/src:${PYTHONPATH:-}"
atlas() { /usr/bin/python3 -m asg_agent.cli.atlas "$@" | grep -v '^skipped' ; }
cd "$REPO"
# every export but those recorded before a fix of what they measured
mapfile -t all < <(find results -name '*.jsonl.gz' -not -path '*/before_the_fix/*' | sort)
atlas build --kind flaw --like results/distinct_v4/dist4-default-s30.jsonl.gz --out results/atlas/exp1-flaw.json "${all[@]}"
atlas build --kind flaw --like results/distinct_v4_transfer/dist4exp3-default-s60.jsonl.gz --out results/atlas/exp3-flaw.json "${all[@]}"
atlas build --kind flaw --like results/distinct_v4_transfer/dist4exp6-default-s60.jsonl.gz --out results/atlas/exp6-flaw.json "${all[@]}"
atlas build --kind regression --like results/distinct_v4_transfer/dist4depth-default-s60.jsonl.gz --out results/atlas/depth-rc4-regression.json "${all[@]}"
atlas build --kind failure --like results/distinct_v4_transfer/dist4gapnav-default-s60.jsonl.gz --out results/atlas/gap-nav-failure.json "${all[@]}"
