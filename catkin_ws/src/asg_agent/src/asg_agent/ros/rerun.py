"""rerun: the top scenarios of a campaign, run again on other stacks (issue #11: is a finding the
perception flaw's doing or the layout's?). Reads the campaign's compact export (so it needs only
the repository), runs the top N through the scene workers named (any stack: the full model,
ground-truth labels, another planner grid), and writes one JSON line per scenario with every
proxy term. `summary` turns such files into the flaw-or-layout table of docs/experiments.md.

    python3 -m asg_agent.ros.rerun run EXPORT.jsonl.gz --top 50 --workers 2 --label paper/full --out OUT.jsonl
    python3 -m asg_agent.ros.rerun summary OUT1.jsonl ... --json results/flaw_or_layout.json

`--select proxy` (round 2) re-runs the N scenarios of largest proxy. `--select perception` (round
3, an attributed campaign) re-runs what the campaign blamed on the perception: its perception
findings, then its differential findings, then its perception collisions (the classes of
`CLASSES`), each by proxy, up to N. `summary` then counts, per class, how many still fail the
same way on the stack re-run (a finding: proxy >= 3; differential: proxy at least 1 over the
campaign's reference run; a collision: it collides again).
"""

import argparse
import json
import os
import sys
import time

import numpy as np

from asg_agent.records.export import read_export
from asg_agent.scoring.attribution import FINDING, RERUN_CLASSES, rerun_class, still_failing
from asg_agent.campaign.dispatch import run_each
from asg_agent.scoring.proxy import run_terms, term_values


MAX_ATTEMPTS = 3  # runs of a scenario before its ERROR is kept (as the campaign's max_attempts)

#: What an attributed campaign blamed on the perception, in the order `--select perception` takes it.
CLASSES = RERUN_CLASSES


def campaign_class(row) -> str:
    """The first of CLASSES the campaign row falls in ('' for none, or a row without a reference)."""
    return rerun_class(row)


def top_requests(export: str, top: int, select: str = "proxy"):
    """[(campaign row, request)] to re-run: the `top` of largest proxy, or (select 'perception')
    the perception-attributable ones, class by class. Raises ValueError for an unknown `select`
    or a 'perception' selection from an export without reference runs."""
    from asg_agent.records.scenes import scenario_of

    camp, rows = read_export(export)
    rows = [r for r in rows if r["proxy"] is not None]
    if select == "proxy":
        ranked = sorted(rows, key=lambda r: -r["proxy"])
    elif select == "perception":
        if not any(r.get("reference") for r in rows):
            raise ValueError(f"{export}: no reference runs (an attributed campaign is needed for --select perception)")
        order = {c: k for k, c in enumerate(CLASSES)}
        keyed = [((order[c], -r["proxy"], r["job"]), r) for r in rows if (c := campaign_class(r))]
        ranked = [r for _, r in sorted(keyed, key=lambda kr: kr[0])]
    elif select == "first":  # issue #36: the first N by job, whatever they are (the candidate rule's check)
        ranked = sorted(rows, key=lambda r: r["job"])
    else:
        raise ValueError(f"unknown selection {select!r} (proxy, perception or first)")
    out = []
    for k, r in enumerate(ranked[:top]):
        req = scenario_of(camp, r)
        req["scenario_id"] = 7000 + k
        out.append((r, req))
    return camp, out


def run(a) -> int:
    from asg_agent.ros.pool import WorkerPool
    from asg_agent.campaign.policy import worker_names

    try:
        camp, todo = top_requests(a.export, a.top, a.select)
    except ValueError as e:
        print(f"rerun: {e}", file=sys.stderr)
        return 2
    from asg_agent.ros.node import init_node

    init_node("rerun", anonymous=True, disable_signals=True)
    pool = WorkerPool(worker_names(a.workers), answer_timeout=300.0)
    results = {}
    t0 = time.time()

    def keep(k, o):
        row, req = todo[o.job]
        terms = run_terms(req, o, dtype=o.trajectory.dtype)[1]
        results[o.job] = {
            "label": a.label,
            "campaign": camp["name"],
            "job": row["job"],
            "rank": o.job + 1,
            "campaign_proxy": row["proxy"],
            "campaign_termination": row["termination"],
            "campaign_reference_proxy": (row.get("reference") or {}).get("proxy"),
            "campaign_class": campaign_class(row),
            "campaign_attribution": row.get("attribution"),
            "termination": o.termination,
            "collision_with": o.collision_with,  # the store's "layout:instance" ('' for none)
            "error": o.error,
            **term_values(terms),
            "sim_time": o.sim_time,
        }
        print(
            f"[{len(results)}/{len(todo)}] rank {o.job + 1}: campaign proxy {row['proxy']:.2f} -> "
            f"{a.label} {results[o.job]['proxy'] if terms else 'ERROR'}",
            file=sys.stderr,
        )

    run_each(pool, [req for _, req in todo], keep, 0.2, MAX_ATTEMPTS)
    os.makedirs(os.path.dirname(os.path.abspath(a.out)) or ".", exist_ok=True)
    with open(a.out, "w") as f:
        for k in sorted(results):
            f.write(json.dumps(results[k]) + "\n")
    print(f"{a.out}: {len(results)} re-runs in {time.time() - t0:.0f} s")
    return 0


def by_class(rows) -> dict:
    """{class: {runs, still}} over the re-runs of an attributed campaign's selection ({} for a
    round-2 file, whose rows carry no class)."""
    out = {}
    for r in rows:
        c = r.get("campaign_class")
        if c:
            e = out.setdefault(c, {"runs": 0, "still": 0})
            e["runs"] += 1
            e["still"] += still_failing(r)
    return out


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
                "still_ge3": sum(v >= FINDING for v in p),
                "dropped": sum(v < FINDING for v in p),
                "errors": len(rows) - len(p),
                "median_proxy": float(np.median(p)) if p else None,
                "campaign_median_proxy": float(np.median([r["campaign_proxy"] for r in rows])),
                "by_class": by_class(rows),
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
    r.add_argument(
        "--select",
        choices=("proxy", "perception", "first"),
        default="proxy",
        help="proxy: the top by proxy; perception: the attributed campaign's perception findings, "
        "differential findings and perception collisions, in that order; first: the first N by job "
        "(every one, candidate or not: what the candidate rule missed, analysis.candidates)",
    )
    s = sub.add_parser("summary")
    s.add_argument("files", nargs="+")
    s.add_argument("--json", required=True)
    a = p.parse_args(argv)
    return run(a) if a.cmd == "run" else summary(a)


if __name__ == "__main__":
    sys.exit(main())
