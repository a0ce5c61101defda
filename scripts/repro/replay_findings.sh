#!/usr/bin/env bash
# Issue #54: every finding of one attribution class of a stored campaign replayed on a worker of
# the campaign's own stack (the experiment's, asg_agent.cli.launch_args), each checked against the
# stored run (asg_agent.ros.replay: REPRODUCED or NOT REPRODUCED), on a master of its own so that
# it can run beside a plan. Writes OUT (JSON: per job the replay's verdict and its last line) and
# exits 1 unless every one is REPRODUCED.
#   bash scripts/repro/replay_findings.sh STORE CAMPAIGN EXPORT [CLASS=flaw] [OUT=results/.../replays/CAMPAIGN.json]
#   e.g. bash scripts/repro/replay_findings.sh results/flaw_study/campaigns.sqlite flaw-default-s10 \
#            results/flaw_study/flaw-default-s10.jsonl.gz
source "$(dirname "${BASH_SOURCE[0]}")/../common.sh"
STORE="${1:?usage: replay_findings.sh STORE CAMPAIGN EXPORT [CLASS] [OUT]}"
CAMPAIGN="${2:?campaign name}"
EXPORT="${3:?the export of the campaign}"
CLASS="${4:-flaw}"
OUT="${5:-$(dirname "$EXPORT")/replays/$CAMPAIGN.json}"
source_ros  # the built workspace (set -u off around its setup.bash)
use_local_master "${ASG_REPLAY_PORT:-11397}" "$REPO/runs/replay_findings/logs"
EXPERIMENT="$(/usr/bin/python3 -c 'import sys; from asg_agent.records.export import read_export
print(read_export(sys.argv[1])[0]["experiment"])' "$EXPORT")"
[ -f "$EXPERIMENT" ] || EXPERIMENT="$REPO/experiments/$EXPERIMENT.yaml"  # the export names it
JOBS="$(/usr/bin/python3 -c 'import sys; from asg_agent.records.export import read_export
print(" ".join(str(r["job"]) for r in read_export(sys.argv[1])[1] if r.get("attribution") == sys.argv[2]))' \
  "$EXPORT" "$CLASS")"
[ -n "$JOBS" ] || { echo "replay_findings: no $CLASS finding in $EXPORT" >&2; exit 2; }
mapfile -t ARGS < <(/usr/bin/python3 -m asg_agent.cli.launch_args experiment:="$EXPERIMENT")
log "$CAMPAIGN: $(wc -w <<< "$JOBS") $CLASS findings, on a worker of ${ARGS[*]}"
trap 'stop_workers; stop_master' EXIT
start_master
start_workers 1 "${ARGS[@]}"
mkdir -p "$(dirname "$OUT")" "$REPO/runs/replay_findings"
LINES="$REPO/runs/replay_findings/$CAMPAIGN.txt"
: > "$LINES"
for job in $JOBS; do
  last="$(/usr/bin/python3 -m asg_agent.ros.replay "$STORE" "$CAMPAIGN" "$job" --worker /worker_0 2>&1 | tail -1)" || true  # its verdict is in the line
  printf '%s\t%s\n' "$job" "$last" | tee -a "$LINES"
done
/usr/bin/python3 - "$LINES" "$OUT" "$CAMPAIGN" "$CLASS" "$(git -C "$REPO" rev-parse --short HEAD)" <<'EOF'
import json, sys
from asg_perception.numerics import DEFAULT_BACKEND, identity
lines, out, campaign, cls, commit = sys.argv[1:]
jobs = {}
for line in open(lines, encoding="utf-8"):
    job, last = line.rstrip("\n").split("\t", 1)
    jobs[job] = {"verdict": "REPRODUCED" if last == "REPRODUCED" else "NOT REPRODUCED", "last_line": last}
ok = sum(j["verdict"] == "REPRODUCED" for j in jobs.values())
with open("/proc/cpuinfo", encoding="utf-8") as f:
    cpu = next((ln.split(":", 1)[1].strip() for ln in f if ln.startswith("model name")), "")
doc = {"campaign": campaign, "class": cls, "findings": len(jobs), "reproduced": ok, "commit": commit,
       "cpu": cpu, "numerics": identity(DEFAULT_BACKEND, 1), "jobs": jobs}
with open(out, "w", encoding="utf-8") as f:
    json.dump(doc, f, indent=1, sort_keys=True)
    f.write("\n")
print(f"{out}: {ok} of {len(jobs)} {cls} findings REPRODUCED")
sys.exit(0 if ok == len(jobs) else 1)
EOF
