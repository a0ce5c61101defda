"""rerun: the top scenarios of a campaign, run again on other stacks (issue #11: is a finding the
perception flaw's doing or the layout's?). Reads the campaign's compact export (so it needs only
the repository), runs the top N through the scene workers named (any stack: the full model,
ground-truth labels, another planner grid), and writes one JSON line per scenario with every
proxy term. `summary` turns such files into the flaw-or-layout table of docs/experiments.md.

    python3 -m asg_agent.ros.rerun run EXPORT.jsonl.gz --top 50 --workers 2 --label full-paper --out OUT.jsonl
    python3 -m asg_agent.ros.rerun summary --campaign EXPORT.jsonl.gz OUT1.jsonl ... --json results/flaw_or_layout.json
"""

import argparse
import json
import os
import sys
import time

import numpy as np

from asg_agent.analysis.export import read_export
from asg_agent.scoring.proxy import run_terms


def top_requests(export: str, top: int):
    from asg_agent.analysis.experiments import scenario_of

    camp, rows = read_export(export)
    ranked = sorted((r for r in rows if r["proxy"] is not None), key=lambda r: -r["proxy"])[:top]
    out = []
    for k, r in enumerate(ranked):
        req = scenario_of(camp, r)
        req["scenario_id"] = 7000 + k
        out.append((r, req))
    return camp, out


def run(a) -> int:
    import rospy
    from asg_agent.ros.pool import WorkerPool
    from asg_agent.cli.campaign import worker_names

    camp, todo = top_requests(a.export, a.top)
    rospy.init_node("rerun", anonymous=True, disable_signals=True)
    pool = WorkerPool(worker_names(a.workers), answer_timeout=300.0)
    pending = list(range(len(todo)))
    results = {}
    attempts = {}
    t0 = time.time()
    while len(results) < len(todo):
        for w in pool.free():
            if not pending:
                break
            k = pending.pop(0)
            attempts[k] = attempts.get(k, 0) + 1
            pool.submit(w, k, todo[k][1])
        for o in pool.poll(0.2):
            if o.termination == "ERROR" and attempts[o.job] < 3:
                pending.insert(0, o.job)
                continue
            row, req = todo[o.job]
            terms = run_terms(req, o, dtype=o.trajectory.dtype)[1]
            results[o.job] = {
                "label": a.label,
                "campaign": camp["name"],
                "job": row["job"],
                "rank": o.job + 1,
                "campaign_proxy": row["proxy"],
                "termination": o.termination,
                "error": o.error,
                "proxy": terms.proxy if terms else None,
                "vis": terms.vis if terms else None,
                "yaw_term": terms.yaw_term if terms else None,
                "plr": terms.plr if terms else None,
                "sim_time": o.sim_time,
            }
            print(
                f"[{len(results)}/{len(todo)}] rank {o.job + 1}: campaign proxy {row['proxy']:.2f} -> "
                f"{a.label} {results[o.job]['proxy'] if terms else 'ERROR'}",
                file=sys.stderr,
            )
    os.makedirs(os.path.dirname(os.path.abspath(a.out)) or ".", exist_ok=True)
    with open(a.out, "w") as f:
        for k in sorted(results):
            f.write(json.dumps(results[k]) + "\n")
    print(f"{a.out}: {len(results)} re-runs in {time.time() - t0:.0f} s")
    return 0


def summary(a) -> int:
    out = []
    for path in a.files:
        with open(path) as f:
            rows = [json.loads(line) for line in f if line.strip()]
        if not rows:
            continue
        grid, _, stack = rows[0]["label"].partition("/")
        p = [r["proxy"] for r in rows if r["proxy"] is not None]
        out.append(
            {
                "grid": grid,
                "stack": stack,
                "file": os.path.basename(path),
                "runs": len(rows),
                "still_ge3": sum(v >= 3 for v in p),
                "dropped": sum(v < 3 for v in p),
                "errors": len(rows) - len(p),
                "median_proxy": float(np.median(p)) if p else None,
                "campaign_median_proxy": float(np.median([r["campaign_proxy"] for r in rows])),
            }
        )
    with open(a.json, "w") as f:
        json.dump({"summary": out}, f, indent=1)
    for s in out:
        print(json.dumps(s))
    return 0


def main(argv=None):
    p = argparse.ArgumentParser(prog="rerun", description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("export")
    r.add_argument("--top", type=int, default=50)
    r.add_argument("--workers", default="2")
    r.add_argument("--label", required=True, help="GRID/STACK, e.g. paper/full")
    r.add_argument("--out", required=True)
    s = sub.add_parser("summary")
    s.add_argument("files", nargs="+")
    s.add_argument("--json", required=True)
    a = p.parse_args(argv)
    return run(a) if a.cmd == "run" else summary(a)


if __name__ == "__main__":
    sys.exit(main())
