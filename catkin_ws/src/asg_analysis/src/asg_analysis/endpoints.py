"""Study endpoints over a campaign's exported rows (issue #78): findings, distinct findings at each
radius, distinct layouts and failure modes, per 1,000 scenarios and per CPU-hour; and a comparison
of arms over seeds. A library: a study names its exports and arms, this computes. No ROS.

    python3 -m asg_analysis endpoints EXPORT.jsonl.gz [...] [--markdown]  # one line (row) per campaign
    python3 -m asg_analysis endpoints EXPORT.jsonl.gz [...] --doc PAGE BLOCK  # the table into PAGE's block
    python3 -m asg_analysis endpoints --arm default=GLOB --arm route-random=GLOB [--budget 300]
                                  [--markdown | --doc PAGE BLOCK]      # arms compared (JSON, or the table)

A finding is a row of the target class (`flaw` with three-stack attribution, `regression` with a
release, else a run that failed: asg_analysis.rules.is_finding); its place and the distinct count
are asg_agent.scoring.places's, the one definition the campaign and the search use (protocol v4).
"""

import argparse
import glob
import json
import sys
from typing import Dict, List, Optional

from asg_agent.scoring.places import PRIMARY_RADIUS_M, REPORTED_RADII_M, count_distinct, place_of_row

PROG = "python3 -m asg_analysis endpoints"

LAYOUT_DISTINCT_M = 2.0  # [m] the project's layout distance (campaign_metrics.layout_distance) for distinct layouts


def campaign(camp: dict, rows: List[dict], budget: Optional[int] = None, target: Optional[str] = "flaw") -> Dict:
    """The endpoints of one campaign over its first `budget` jobs (all when None)."""
    from asg_agent.records import failure_modes as fm
    from asg_analysis.campaign_metrics import _is_new
    from asg_analysis.rules import is_finding

    rows = sorted(rows, key=lambda r: r["job"])
    if budget is not None:
        rows = [r for r in rows if r["job"] < budget]
    found = [r for r in rows if is_finding(r, target)]
    places = [place_of_row(r) for r in found]
    n = max(1, len(rows))
    hours = cpu_hours(camp)
    out = {
        "campaign": camp.get("name"),
        "seed": camp.get("seed"),
        "scenarios": len(rows),
        "findings": len(found),
        "distinct": {f"{r:g}": count_distinct(places, r) for r in REPORTED_RADII_M},
        "distinct_layouts": sum(_is_new(found, LAYOUT_DISTINCT_M)) if found else 0,
        "modes": fm.distinct(fm.modes_of(camp, found)) if found else 0,
        "cpu_hours": hours,
    }
    out["per_1000"] = {k: 1000.0 * v / n for k, v in out["distinct"].items()}
    out["findings_per_1000"] = 1000.0 * len(found) / n
    primary = out["distinct"][f"{PRIMARY_RADIUS_M:g}"]
    out["per_cpu_hour"] = primary / hours if hours else None
    return out


def cpu_hours(camp: dict) -> Optional[float]:
    """The campaign's measured CPU-hours (every process of the run, references included), as
    protocol.py measures them; None when the export holds no measure."""
    from asg_analysis.exports import settings_of
    from asg_analysis.protocol_analysis import measured_cpu_hours

    return measured_cpu_hours(settings_of(camp))


def compare(arms: Dict[str, List[str]], default: str, budget: Optional[int], target: Optional[str] = "flaw") -> Dict:
    """Arms (name -> exports) against the default: per-seed distinct findings (2 m) per 1,000, the
    ratio of means with its bootstrap interval and the exact Mann-Whitney test (stats.compare)."""
    from asg_agent.records.export import read_export
    from asg_analysis import stats

    per = {}
    for arm, paths in arms.items():
        per[arm] = [campaign(*read_export(p), budget=budget, target=target) for p in sorted(paths)]
    key = f"{PRIMARY_RADIUS_M:g}"
    rows = stats.compare({a: [c["per_1000"][key] for c in cs] for a, cs in per.items()}, default)
    return {"campaigns": per, "primary": rows, "per_cpu_hour": within_blocks(per, default)}


def within_blocks(per: Dict[str, List[Dict]], default: str) -> Dict[str, Dict]:
    """Protocol v4's CPU-hour comparison: a block is one seed of every arm run back to back on one
    machine, so the default's campaign and an arm's of the same seed form a block. Per arm: each
    block's ratio of distinct findings (2 m) per CPU-hour, default over arm; their geometric mean;
    the smallest. A block where either side has no CPU measure or the arm found nothing is left out
    and named."""
    import math

    mine = {c["seed"]: c for c in per[default]}
    out = {}
    for arm, cs in per.items():
        if arm == default:
            continue
        blocks, left = [], []
        for c in sorted(cs, key=lambda c: c["seed"]):
            d = mine.get(c["seed"])
            if d is None or not d["per_cpu_hour"] or not c["per_cpu_hour"]:
                left.append(c["seed"])
                continue
            blocks.append(
                {
                    "seed": c["seed"],
                    "default": d["per_cpu_hour"],
                    "arm": c["per_cpu_hour"],
                    "ratio": d["per_cpu_hour"] / c["per_cpu_hour"],
                }
            )
        ratios = [b["ratio"] for b in blocks]
        out[arm] = {
            "blocks": blocks,
            "left_out": left,
            "geomean": math.exp(sum(math.log(r) for r in ratios) / len(ratios)) if ratios else None,
            "min": min(ratios) if ratios else None,
        }
    return out


def comparison_markdown(res: Dict) -> str:
    """The confirmatory table: per arm, the per-seed distinct findings (2 m) per 1,000, the mean
    with its interval, the default's ratio with its interval and the exact test, and the ratios per
    CPU-hour within blocks with their geometric mean."""
    out = [
        "| arm | seeds | distinct per 1,000 at 2 m, per seed | mean (95 % interval) | default / arm (95 % interval) | exact p | per CPU-hour, default / arm, by block | geometric mean |",
        "|---|---|---|---|---|---|---|---|",
    ]
    blocks = res["per_cpu_hour"]
    for r in res["primary"]:
        cells = [
            r["arm"],
            str(r["seeds"]),
            ", ".join(f"{v:.1f}" for v in r["counts"]),
            f"{r['mean']:.1f} ({r['lo']:.1f}-{r['hi']:.1f})",
        ]
        if r["ratio"] is None:
            cells += ["-", "-", "-", "-"]
        else:
            b = blocks[r["arm"]]
            cells += [
                f"{r['ratio']:.2f}x ({r['ratio_lo']:.2f}-{r['ratio_hi']:.2f})",
                f"{r['p']:.4f}",
                ", ".join(f"s{x['seed']} {x['ratio']:.2f}" for x in b["blocks"]) or "-",
                f"{b['geomean']:.2f}x" if b["geomean"] is not None else "-",
            ]
        out.append("| " + " | ".join(cells) + " |")
    return "\n".join(out)


def line(c: Dict) -> str:
    d = c["distinct"]
    return (
        f"{c['campaign']}: {c['scenarios']} scenarios, {c['findings']} findings, distinct "
        + ", ".join(f"{v} at {k} m" for k, v in d.items())
        + f" ({c['per_1000'][f'{PRIMARY_RADIUS_M:g}']:.1f} per 1,000 at {PRIMARY_RADIUS_M:g} m), "
        f"{c['distinct_layouts']} distinct layouts, {c['modes']} modes"
    )


def markdown(cs: List[Dict], target: Optional[str] = "flaw") -> str:
    """A table of campaigns' endpoints, one row each (what docs/experiments.md's blocks hold); the
    findings column names the target class (a failure where target is None)."""
    out = [
        f"| campaign | scenarios | {target or 'failure'} findings | distinct at 1 / 2 / 5 m | distinct per 1,000 (2 m) "
        "| distinct layouts | modes |",
        "|---|---|---|---|---|---|---|",
    ]
    for c in cs:
        d = c["distinct"]
        out.append(
            f"| {c['campaign']} | {c['scenarios']} | {c['findings']} | {d['1']} / {d['2']} / {d['5']} | "
            f"{c['per_1000']['2']:.1f} | {c['distinct_layouts']} | {c['modes']} |"
        )
    return "\n".join(out)


def write_block(doc: str, block: str, text: str) -> None:
    """Writes `text` as block BLOCK of `doc` (docblocks.rewrite; ValueError when it has none)."""
    from asg_analysis.docblocks import rewrite

    if rewrite(doc, {block: text}, check=False, prog=PROG) == 2:
        raise ValueError(f"{doc}: no block {block!r}")


def run(argv=None) -> int:
    p = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    p.add_argument("exports", nargs="*")
    p.add_argument("--arm", action="append", default=[], help="NAME=GLOB of exports (the first is the default)")
    p.add_argument("--budget", type=int, default=None, help="count the first N jobs")
    p.add_argument("--target", default="flaw", help="flaw, regression or failure")
    p.add_argument("--markdown", action="store_true", help="the exports as one table")
    p.add_argument("--doc", nargs=2, metavar=("PAGE", "BLOCK"), help="write the table into PAGE's block BLOCK")
    a = p.parse_args(argv)
    target = None if a.target == "failure" else a.target
    from asg_agent.records.export import read_export

    try:
        if a.arm:
            arms = {}
            for spec in a.arm:
                name, _, pattern = spec.partition("=")
                arms[name] = glob.glob(pattern)
                if not arms[name]:
                    raise ValueError(f"--arm {spec}: no export matches")
            res = compare(arms, next(iter(arms)), a.budget, target)
            if a.doc:
                write_block(a.doc[0], a.doc[1], comparison_markdown(res))
                return 0
            print(comparison_markdown(res) if a.markdown else json.dumps(res, indent=1, default=str))
            return 0
        cs = [campaign(*read_export(path), budget=a.budget, target=target) for path in sorted(a.exports)]
        if a.doc:
            write_block(a.doc[0], a.doc[1], markdown(cs, target))
        elif cs:
            print(markdown(cs, target) if a.markdown else "\n".join(line(c) for c in cs))
    except (OSError, ValueError) as e:
        print(f"endpoints: {e}", file=sys.stderr)
        return 2
    return 0
