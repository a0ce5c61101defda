#!/usr/bin/env bash
# Issue #40: record a regression suite's outcomes on stacks, one worker each, on a private master.
#   bash scripts/repro/suite_record.sh SUITE LABEL=WORKER_ARGS [LABEL=WORKER_ARGS ...]
# e.g. bash scripts/repro/suite_record.sh tests/suites/exp1c-flaw "full=perception:=unet model:=full" \
#          "flawed=perception:=unet model:=flawed"
# Each label's outcomes (termination, proxy, trajectory digest) go into SUITE/suite.yaml.
# ASG_SUITE_WORKERS=N runs N workers a stack (default 1; runs are deterministic either way).
# ASG_SUITE_JSON=DIR also writes each label's results, paths driven included, to DIR/LABEL.json
# (for `python3 -m asg_analysis hardening picture`).
source "$(dirname "${BASH_SOURCE[0]}")/../common.sh"
SUITE="$1"
shift
install_packages
build_workspace ON
use_local_master "${ASG_SUITE_PORT:-11394}" "$REPO/runs/suite/logs"
trap 'stop_workers; stop_master' EXIT
start_master
for spec in "$@"; do
  label="${spec%%=*}"
  read -ra args <<< "${spec#*=}"
  log "suite $SUITE on $label (${args[*]})"
  start_workers "${ASG_SUITE_WORKERS:-1}" "${args[@]}"
  json=()
  [ -z "${ASG_SUITE_JSON:-}" ] || { mkdir -p "$ASG_SUITE_JSON" && json=(--json "$ASG_SUITE_JSON/$label.json"); }
  /usr/bin/python3 -m asg_agent.cli.suite run "$SUITE" --workers "${ASG_SUITE_WORKERS:-1}" --record "$label" "${json[@]}"
  stop_workers
done
