"""Findings over the budget (issue #67, no ROS): how many findings of one attribution class each
campaign made in each block of its budget, arm by arm. A search that learns from its results finds
more as its budget goes on; a sampler that learns nothing (route-random) stays level.

    python3 -m asg_analysis learning-curve results/flaw_study3 \
        --arm default=flaw3-default-s10,flaw3-default-s11 --arm route-random=flaw3-route-random-s10 \
        [--budget 300] [--block 30] [--target flaw] [--markdown] [--json out.json] [--figure out.png]

Jobs are counted by their job number (the order the search proposed them), only those below the
budget; a block of `block` jobs holds jobs [k * block, (k + 1) * block).
"""

import argparse
import os
import sys
from typing import Dict, List

PROG = "python3 -m asg_analysis learning-curve"


def blocks(rows: List[dict], budget: int, block: int, target: str = "flaw") -> List[int]:
    """Findings of class `target` in each block of `block` jobs below `budget`."""
    if block < 1 or budget < block:
        raise ValueError(f"learning_curve: block {block} must be >= 1 and at most the budget {budget}")
    out = [0] * -(-budget // block)
    for r in rows:
        if 0 <= r["job"] < budget and r.get("attribution") == target:
            out[r["job"] // block] += 1
    return out


def curves(folder: str, arms: Dict[str, List[str]], budget: int, block: int, target: str = "flaw") -> dict:
    """{arm: {campaign: [findings per block]}} read from FOLDER/NAME.jsonl.gz."""
    from asg_agent.records.export import read_export

    out = {}
    for arm, names in arms.items():
        out[arm] = {}
        for name in names:
            path = os.path.join(folder, name + ".jsonl.gz")
            if not os.path.isfile(path):
                raise OSError(f"learning_curve: no export {path}")
            out[arm][name] = blocks(read_export(path)[1], budget, block, target)
    return {"curves": out, "budget": budget, "block": block, "target": target}


def _mean(xs: List[float]) -> float:
    return sum(xs) / len(xs)


def markdown(res: dict) -> str:
    """One row a block: each arm's mean findings over its campaigns, and each campaign's count."""
    arms, b = res["curves"], res["block"]
    n = len(next(iter(next(iter(arms.values())).values())))
    head = " | ".join(f"{arm}: mean (per campaign)" for arm in arms)
    lines = [f"| jobs | {head} |", "|---|" + "---|" * len(arms)]
    for k in range(n):
        cells = []
        for per in arms.values():
            counts = [c[k] for c in per.values()]
            cells.append(f"{_mean(counts):.1f} ({', '.join(map(str, counts))})")
        lines.append(f"| {k * b}-{min((k + 1) * b, res['budget']) - 1} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def figure(res: dict, out: str) -> Dict[str, List[float]]:
    """Each arm's mean findings a block (thick) and each campaign's (thin); returns the means drawn."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    b, t = res["block"], res["target"]
    fig, ax = plt.subplots(figsize=(7.5, 4.0))
    drawn = {}
    for i, (arm, per) in enumerate(res["curves"].items()):
        colour = f"C{i}"
        series = list(per.values())
        x = [k * b + b / 2 for k in range(len(series[0]))]
        for s in series:
            ax.plot(x, s, color=colour, alpha=0.3, linewidth=0.8)
        drawn[arm] = [_mean([s[k] for s in series]) for k in range(len(x))]
        ax.plot(x, drawn[arm], color=colour, linewidth=2.2, marker="o", label=f"{arm} ({len(series)} campaigns)")
    ax.set_xlabel(f"job (the order proposed), blocks of {b}")
    ax.set_ylabel(f"{t} findings a block")
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=9)
    ax.set_title(f"{t} findings over the budget: mean over campaigns (thick) and each campaign (thin)", fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return drawn


def run(argv=None) -> int:
    ap = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    ap.add_argument("folder", help="the exports' folder")
    ap.add_argument("--arm", action="append", required=True, help="NAME=CAMPAIGN,CAMPAIGN,... (repeat per arm)")
    ap.add_argument("--budget", type=int, default=300, help="[scenarios] jobs counted per campaign (300)")
    ap.add_argument("--block", type=int, default=30, help="[scenarios] jobs a block (30)")
    ap.add_argument("--target", default="flaw", help="the attribution class of a finding (flaw; regression)")
    ap.add_argument("--markdown", action="store_true")
    ap.add_argument("--json", default="")
    ap.add_argument("--figure", default="", help="a PNG of the curves")
    a = ap.parse_args(argv)
    arms = {}
    for spec in a.arm:
        name, sep, names = spec.partition("=")
        if not sep or not name or not names:
            print(f"learning_curve: --arm {spec!r} is not NAME=CAMPAIGN,CAMPAIGN,...", file=sys.stderr)
            return 2
        arms[name] = [n for n in names.split(",") if n]
    try:
        res = curves(a.folder, arms, a.budget, a.block, a.target)
    except (OSError, ValueError, KeyError) as e:
        print(str(e), file=sys.stderr)
        return 2
    from asg_analysis.files import report

    return report(res, a.json, figure, a.figure, markdown, a.markdown)
