"""Run-to-run spread of a free-running stack (issue #55): the same stored scenarios run again
several times (asg_agent.ros.rerun, one output file a repetition), and how often each outcome
repeats. A lockstep stack repeats every run bit for bit; a free-running one (no client of this
project: what a command saw depends on thread timing and load) may not, so its findings are only
as good as the share that fail again. No ROS.

Per scenario: the stored verdict (attribution.RunOutcome.fails: collision, timeout, flip, out of
bounds, or proxy >= FINDING) and each repetition's; the scenario *repeats* when every repetition's
verdict equals the stored one. Reported: scenarios, repetitions, the share that repeat (with an
exact 95 % interval), the stored failures that fail again in every repetition, in some, in none,
and each scenario's proxy range over the stored run and its repetitions.

    python3 -m asg_analysis run-spread EXPORT.jsonl.gz r1.jsonl r2.jsonl ... [--json OUT] [--markdown]
"""

import argparse
import json
import sys
from typing import Dict, List

import numpy as np

from asg_agent.records.export import read_export
from asg_agent.scoring.attribution import RunOutcome
from asg_analysis.stats import exact_interval
from asg_analysis.files import write_json


def read_reruns(paths: List[str]) -> List[Dict[int, dict]]:
    """One {job: row} per repetition file; ValueError naming a file that holds a job twice."""
    out = []
    for path in paths:
        rows = {}
        with open(path, encoding="utf-8") as f:
            for line in f:
                if line.strip():
                    r = json.loads(line)
                    if r["job"] in rows:
                        raise ValueError(f"{path}: job {r['job']} twice")
                    rows[r["job"]] = r
        out.append(rows)
    return out


def spread(export: str, reruns: List[str]) -> Dict:
    camp, rows = read_export(export)
    stored = {r["job"]: r for r in rows}
    reps = read_reruns(reruns)
    jobs = sorted(set.intersection(*(set(r) for r in reps))) if reps else []
    if not jobs:
        raise ValueError("no scenario was run in every repetition")
    missing = sorted(set().union(*(set(r) for r in reps)) - set(jobs))
    if missing:
        raise ValueError(f"jobs {missing} are missing from some repetitions")
    unknown = [j for j in jobs if j not in stored]
    if unknown:
        raise ValueError(f"jobs {unknown} are not in {export}")
    per = []
    for j in jobs:
        first = RunOutcome.of(stored[j])
        again = [RunOutcome.of(r[j]) for r in reps]
        proxies = [o.proxy for o in [first] + again if o.proxy is not None]
        per.append(
            {
                "job": j,
                "stored": {"termination": first.termination, "proxy": first.proxy, "fails": first.fails},
                "again": [{"termination": o.termination, "proxy": o.proxy, "fails": o.fails} for o in again],
                "fails_again": sum(o.fails for o in again),
                "repeats": all(o.fails == first.fails for o in again),
                "proxy_range": (max(proxies) - min(proxies)) if proxies else None,
            }
        )
    n, k = len(per), sum(p["repeats"] for p in per)
    failed = [p for p in per if p["stored"]["fails"]]
    ranges = [p["proxy_range"] for p in per if p["proxy_range"] is not None]
    return {
        "campaign": camp["name"],
        "scenarios": n,
        "repetitions": len(reps),
        "repeat": k,
        "repeat_share": k / n,
        "repeat_interval": exact_interval(k, n),
        "stored_failures": len(failed),
        "failures_fail_again": {
            "always": sum(p["fails_again"] == len(reps) for p in failed),
            "sometimes": sum(0 < p["fails_again"] < len(reps) for p in failed),
            "never": sum(p["fails_again"] == 0 for p in failed),
        },
        "proxy_range_median": float(np.median(ranges)) if ranges else None,
        "proxy_range_max": max(ranges) if ranges else None,
        "per_scenario": per,
    }


def markdown(s: Dict) -> str:
    lo, hi = s["repeat_interval"]
    f = s["failures_fail_again"]
    rows = [
        "| campaign | scenarios x repetitions | verdict repeats in every repetition (95 % exact) "
        "| stored failures: fail again always / sometimes / never | proxy range: median / largest |",
        "|---|---|---|---|---|",
        f"| {s['campaign']} | {s['scenarios']} x {s['repetitions']} | {s['repeat']} of {s['scenarios']} "
        f"({100 * s['repeat_share']:.0f} %, {100 * lo:.0f}-{100 * hi:.0f} %) | {s['stored_failures']}: "
        f"{f['always']} / {f['sometimes']} / {f['never']} | "
        + (
            f"{s['proxy_range_median']:.3f} / {s['proxy_range_max']:.3f} |"
            if s["proxy_range_median"] is not None
            else "- |"
        ),
    ]
    return "\n".join(rows)


def run(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("export", help="the campaign's export (NAME.jsonl.gz) the scenarios came from")
    p.add_argument("reruns", nargs="+", help="asg_agent.ros.rerun outputs, one a repetition")
    p.add_argument("--json", default="", help="write the figures here")
    p.add_argument("--markdown", action="store_true", help="print the table as docs/your-stack.md shows it")
    a = p.parse_args(argv)
    try:
        s = spread(a.export, a.reruns)
    except (OSError, ValueError, KeyError) as e:
        print(f"run_spread: {e}", file=sys.stderr)
        return 2
    if a.json:
        write_json(a.json, s)
    print(markdown(s) if a.markdown else json.dumps({k: v for k, v in s.items() if k != "per_scenario"}, indent=1))
    return 0
