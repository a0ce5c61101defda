"""How each arm of the flaw study spends its budget (issue #54's "why", no ROS): per arm, over its
confirmatory seeds, flaw findings per window of scenarios in job order (does a search improve as
it learns, and what its warm-up costs), where it places obstacles relative to the route (the
lateral offset of every obstacle, and of the obstacle each flaw collision hit), and the share of
its scenarios that are candidates re-run on the references (what attribution costs it).

    python3 -m asg_analysis budget results/flaw_study --figure docs/images/flaw_study_budget.png

Read by `protocol analyse --doc` once every confirmatory campaign is in (it writes the table and
the figure beside the result)."""

import argparse
import os
import re
import sys
from typing import Dict, List

import numpy as np

PROG = "python3 -m asg_analysis budget"

WINDOW = 50  # [scenarios] the learning curve's window, in job order
NEAR = 2.0  # [m] an obstacle this close to the route's line is "on the route" for the table


def offsets(campaign: dict, row: dict) -> np.ndarray:
    """|lateral offset| [m] of each obstacle of a row from the straight start-goal line."""
    from asg_agent.records.scenes import scenario_of
    from asg_scenario.layout import RouteFrame

    f = RouteFrame(scenario_of(campaign, row))
    p = np.asarray(row["positions"], float).reshape(-1, 2)
    return np.abs((p - f.start) @ f.normal)


def arm_budget(campaigns: Dict[int, tuple], budget: int, cls: str = "flaw") -> dict:
    """{curve: findings of class `cls` (flaw, or a stack pair's regression) per 1,000 per window
    (mean over seeds), placed: every obstacle's |offset|, hit: the |offset| of the obstacle each
    such collision hit, candidates: share re-run, near: share of obstacles within NEAR of the
    route} over the seeds {seed: (campaign, rows)}."""
    curves, placed, hit, cand = [], [], [], []
    for camp, rows in campaigns.values():
        rows = sorted((r for r in rows if r["job"] < budget), key=lambda r: r["job"])
        flaw = np.array([r.get("attribution") == cls for r in rows], float)
        curves.append([1000.0 * flaw[i : i + WINDOW].mean() for i in range(0, len(rows), WINDOW)])
        cand.append(np.mean([r.get("attribution") not in (None, "", "not_candidate") for r in rows]))
        for r in rows:
            d = offsets(camp, r)
            placed.append(d)
            if r.get("attribution") == cls and r.get("collision_with") is not None:
                hit.append(d[r["collision_with"]])
    placed = np.concatenate(placed) if placed else np.zeros(0)
    n = min(len(c) for c in curves)
    return {
        "curve": np.mean([c[:n] for c in curves], axis=0).tolist(),
        "placed": placed,
        "hit": np.asarray(hit, float),
        "candidates": float(np.mean(cand)),
        "near": float(np.mean(placed < NEAR)) if placed.size else 0.0,
    }


def read(folder: str, budget: int = 300, prefix: str = "flaw", cls: str = "flaw") -> Dict[str, dict]:
    """Every complete confirmatory export of the study in `folder` (PREFIX-ARM-sSEED), by arm,
    counting the endpoint's class `cls`."""
    from asg_agent.records.export import read_export

    arms: Dict[str, Dict[int, tuple]] = {}
    for name in sorted(os.listdir(folder)):
        m = re.fullmatch(re.escape(prefix) + r"-(.+)-s(\d+)\.jsonl\.gz", name)
        if not m or m.group(1).startswith("pilot-"):
            continue
        camp, rows = read_export(os.path.join(folder, name))
        if len({r["job"] for r in rows if r["job"] < budget}) >= budget:
            arms.setdefault(m.group(1), {})[int(m.group(2))] = (camp, rows)
    return {arm: dict(arm_budget(seeds, budget, cls), seeds=len(seeds), cls=cls) for arm, seeds in arms.items()}


def markdown(res: Dict[str, dict], order: List[str]) -> str:
    cls = next((r.get("cls", "flaw") for r in res.values()), "flaw")
    lines = [
        f"| arm | seeds | {cls} per 1,000 by {WINDOW}-scenario window (mean over seeds) | obstacles within {NEAR:g} m "
        f"of the route | median offset of obstacles placed / of those a {cls} collision hit [m] | candidates re-run |",
        "|---|---|---|---|---|---|",
    ]
    for arm in [a for a in order if a in res]:
        r = res[arm]
        hit = f"{np.median(r['hit']):.1f}" if r["hit"].size else "-"
        lines.append(
            f"| {arm} | {r['seeds']} | {', '.join(f'{v:.0f}' for v in r['curve'])} | {100 * r['near']:.0f} % | "
            f"{np.median(r['placed']):.1f} / {hit} | {100 * r['candidates']:.0f} % |"
        )
    return "\n".join(lines)


def figure(res: Dict[str, dict], order: List[str], out: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    arms = [a for a in order if a in res]
    cls = next((res[a].get("cls", "flaw") for a in arms), "flaw")
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 3.6))
    for arm in arms:
        c = res[arm]["curve"]
        a1.plot(np.arange(len(c)) * WINDOW + WINDOW / 2, c, marker="o", label=arm)
    a1.set_xlabel("scenarios spent")
    a1.set_ylabel(f"{cls} findings per 1,000 ({WINDOW}-scenario windows)")
    a1.grid(alpha=0.3)
    a1.legend(fontsize=7)
    x = np.linspace(0.0, 20.0, 201)
    for k, arm in enumerate(arms):
        placed, hit = np.sort(res[arm]["placed"]), np.sort(res[arm]["hit"])
        color = f"C{k}"
        a2.plot(x, np.searchsorted(placed, x, side="right") / max(1, placed.size), color=color, label=f"{arm}: placed")
        if hit.size:
            a2.plot(
                x, np.searchsorted(hit, x, side="right") / hit.size, color=color, ls="--", label=f"{arm}: hit ({cls})"
            )
    a2.set_xlabel("|offset| from the start-goal line [m]")
    a2.set_ylabel("share of obstacles within it")
    a2.set_xlim(0, 20)
    a2.set_ylim(0, 1.02)
    a2.grid(alpha=0.3)
    a2.legend(fontsize=6)
    fig.suptitle(
        f"How each arm spends its budget: {cls} findings as it goes (left); how close to the route it puts "
        f"obstacles, all of them and those a {cls} collision hit (right)",
        fontsize=9,
    )
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    plt.close(fig)


def run(argv=None) -> int:
    ap = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    ap.add_argument("folder")
    ap.add_argument("--budget", type=int, default=300)
    ap.add_argument("--figure", default="")
    a = ap.parse_args(argv)
    res = read(a.folder, a.budget)
    if not res:
        print(f"budget: no complete confirmatory export in {a.folder}", file=sys.stderr)
        return 2
    order = ["default", "random", "route-random", "cmaes", "map-elites"]
    order += sorted(set(res) - set(order))
    print(markdown(res, order))
    if a.figure:
        figure(res, order, a.figure)
    return 0
