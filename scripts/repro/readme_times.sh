#!/usr/bin/env bash
# The times of the README's three commands on this machine (issue #79): runs each named command as
# the README writes it, alone, and records its wall time with the CPU it ran on and the commit in
# results/readme_times/COMMAND-DATE.json; python3 scripts/ci/readme_times.py --doc README.md writes
# the README's block from the newest record of each (tests/test_readme_times.py checks it).
#   bash scripts/repro/readme_times.sh demo train test
set -uo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
OUT="$REPO/results/readme_times"
mkdir -p "$OUT"
for name in "$@"; do
  case "$name" in demo | train | test) ;; *) echo "readme_times: $name is not demo, train or test" >&2; exit 2 ;; esac
  fresh=$([ -f "$REPO/catkin_ws/devel/setup.bash" ] && echo false || echo true)
  start=$(date +%s.%N)
  mkdir -p "$REPO/runs/readme_times"
  bash "$REPO/scripts/$name.sh" > "$REPO/runs/readme_times/$name.log" 2>&1  # its console, not committed
  rc=$?
  end=$(date +%s.%N)
  /usr/bin/python3 - "$OUT" "$name" "$start" "$end" "$rc" "$fresh" <<'PY'
import json, os, subprocess, sys, time
out, name, start, end, rc, fresh = sys.argv[1:]
flags = next(l for l in open("/proc/cpuinfo") if l.startswith("flags")).split()
cpu = next(l for l in open("/proc/cpuinfo") if l.startswith("model name")).split(":", 1)[1].strip()
kind = "AMX" if "amx_bf16" in flags else "AVX512-BF16" if "avx512_bf16" in flags else "AVX-512" if "avx512f" in flags else "AVX2-only"
rec = {
    "command": f"bash scripts/{name}.sh",
    "wall_s": round(float(end) - float(start), 1),
    "exit": int(rc),
    "built_before": fresh == "false",
    "cpu": cpu,
    "cpu_kind": kind,
    "cores": os.cpu_count(),
    "commit": subprocess.run(["git", "-C", out, "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip(),
    "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime(float(start))),
}
path = os.path.join(out, f"{name}-{time.strftime('%Y%m%dT%H%M', time.gmtime(float(start)))}.json")
json.dump(rec, open(path, "w"), indent=1, sort_keys=True)
print(json.dumps(rec))
PY
done
