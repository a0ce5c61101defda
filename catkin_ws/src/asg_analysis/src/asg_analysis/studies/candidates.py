"""What the candidate rule missed (issue #36; no ROS): a campaign's first N scenarios re-run on
both reference stacks whatever they were (`rerun run EXPORT --select first --top N`, once per
stack), classed by the one rule of scoring/attribution.py, against what the campaign stored.

    python3 -m asg_analysis candidates EXPORT.jsonl.gz FULL.jsonl GROUND_TRUTH.jsonl [--json OUT]

Prints, for the candidates, whether the full re-run gives each the class the campaign stored
(the runs are deterministic, so it must), and for the scenarios that were not candidates, the
classes they would have had: a flaw, model or stack finding there would be a finding the rule
missed (none can be, by construction), a reverse case one it does not count.
"""

import argparse
import json
import sys

from asg_agent.records.export import read_export
from asg_agent.scoring import attribution as attr

PROG = "python3 -m asg_analysis candidates"


def _read_jsonl(path):
    with open(path) as f:
        return {r["job"]: r for r in (json.loads(line) for line in f if line.strip())}


def check(rows, full: dict, truth: dict) -> dict:
    """rows: the export's rows; full / truth: {job: re-run row} on each reference."""
    jobs = sorted(set(full) & set(truth))
    by_job = {r["job"]: r for r in rows}
    out = {
        "scenarios": len(jobs),
        "candidates": 0,
        "candidates_same_class": 0,
        "candidates_differing": [],
        "not_candidates": {c: 0 for c in attr.CLASSES},
        "missed_findings": [],
        "missed_reverse": [],
    }
    for j in jobs:
        r = by_job[j]
        cls = attr.classify_rows(r, {attr.FULL: full[j], attr.TRUTH: truth[j]})
        if attr.is_candidate(r["termination"], r["proxy"]):
            out["candidates"] += 1
            if cls == r.get("attribution"):
                out["candidates_same_class"] += 1
            else:
                out["candidates_differing"].append({"job": j, "stored": r.get("attribution"), "rerun": cls})
        else:
            out["not_candidates"][cls] += 1
            if cls in attr.FINDINGS:
                out["missed_findings"].append(j)
            elif cls == "reverse":
                out["missed_reverse"].append(j)
    return out


def run(argv=None) -> int:
    p = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    p.add_argument("export")
    p.add_argument("full")
    p.add_argument("ground_truth")
    p.add_argument("--json", default="")
    a = p.parse_args(argv)
    try:
        _, rows = read_export(a.export)
        out = check(rows, _read_jsonl(a.full), _read_jsonl(a.ground_truth))
    except (OSError, ValueError, KeyError) as e:
        print(f"candidates: {e}", file=sys.stderr)
        return 2
    print(
        f"{out['scenarios']} scenarios re-run on both references: {out['candidates']} candidates, "
        f"{out['candidates_same_class']} of them classed as the campaign stored; of the "
        f"{out['scenarios'] - out['candidates']} not candidates: findings missed {len(out['missed_findings'])}, "
        f"reverse cases not counted {len(out['missed_reverse'])} ({', '.join(map(str, out['missed_reverse'])) or '-'})"
    )
    if a.json:
        with open(a.json, "w") as f:
            json.dump(out, f, indent=1, sort_keys=True)
            f.write("\n")
    return 0 if not out["candidates_differing"] else 1
