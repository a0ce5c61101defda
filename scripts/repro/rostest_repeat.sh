#!/usr/bin/env bash
# Runs rostests of asg_tests N times in a row, one at a time, and records each run (issue #68 item
# 4: "20 runs in a row of the affected rostests, on a loaded machine"): the test, the run, its
# result (the rostest summary's counts), its wall time and the machine's 1-minute load average
# when it started, one line each in OUT (a text file, kept in the repository). Stops at nothing: a
# failed run is recorded and the next one starts. What loaded the machine is the caller's to say
# (the first line of OUT holds NOTE).
#   bash scripts/repro/rostest_repeat.sh N OUT NOTE TEST [TEST ...]
#   bash scripts/repro/rostest_repeat.sh 20 results/flaky/r6-repeat.txt "beside a campaign" stack_faults.test
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../common.sh"
N="${1:?usage: rostest_repeat.sh N OUT NOTE TEST...}"
OUT="${2:?}"
NOTE="${3:?}"
shift 3
[ $# -ge 1 ] || { echo "rostest_repeat: name at least one test of asg_tests" >&2; exit 2; }
source_ros
mkdir -p "$(dirname "$OUT")"
LOGS="$(mktemp -d)"
{
  echo "# rostest_repeat: $N runs each of $*, one at a time; $NOTE"
  echo "# CPU: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(nproc) cores; commit $(git -C "$REPO" rev-parse --short HEAD)"
  echo "# test run result tests failures errors wall_s load_1min start_utc"
} > "$OUT"
for t in "$@"; do
  for k in $(seq "$N"); do
    load="$(cut -d' ' -f1 /proc/loadavg)"
    start="$(date -u +%H:%M:%S)"
    t0=$(date +%s.%N)
    rc=0
    "${ASG_ROSTEST:-rostest}" asg_tests "$t" > "$LOGS/$t.$k.log" 2>&1 || rc=$?  # (ASG_ROSTEST: this script's test)
    wall=$(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN {print b - a}')
    # rostest's summary: "SUMMARY ... * RESULT: SUCCESS", "* TESTS: 5", "* ERRORS: 0", "* FAILURES: 0"
    # (rostest colours a failing count: its ANSI escapes are taken out first)
    plain="$(sed 's/\x1b\[[0-9;]*m//g' "$LOGS/$t.$k.log")"
    tests="$(sed -n 's/^ \* TESTS: //p' <<< "$plain" | tail -1)"
    errors="$(sed -n 's/^ \* ERRORS: //p' <<< "$plain" | tail -1)"
    failures="$(sed -n 's/^ \* FAILURES: //p' <<< "$plain" | tail -1)"
    result=PASS
    [ "$rc" -eq 0 ] && [ "${errors:-1}" = 0 ] && [ "${failures:-1}" = 0 ] || result=FAIL
    printf '%s %d %s %s %s %s %.1f %s %s\n' "$t" "$k" "$result" "${tests:-?}" "${failures:-?}" "${errors:-?}" \
        "$wall" "$load" "$start" >> "$OUT"
    # a failed run's log is kept beside the record, with the machine's paths made placeholders
    [ "$result" = PASS ] || sed -e "s|$REPO|\$REPO|g" -e "s|${ROS_HOME:-$HOME/.ros}|\$ROS_HOME|g" \
      -e "s|$HOME|~|g" "$LOGS/$t.$k.log" > "${OUT%.txt}-$t-$k.log"
    log "$t run $k: $result in ${wall%.*} s (load $load)"
  done
done
rm -rf "$LOGS"
awk '!/^#/ {n[$1]++; if ($3 == "PASS") p[$1]++} END {for (t in n) printf "%s: %d of %d passed\n", t, p[t], n[t]}' "$OUT"
