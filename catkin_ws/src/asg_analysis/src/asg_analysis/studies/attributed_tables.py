"""Round 3's attributed tables and figures (docs/experiments.md): the search comparison with
every scenario attributed, its figure, Table 2 attributed, and the flaw-or-layout re-runs. No ROS."""

import json
import os

import numpy as np

from asg_agent.records.export import counts
from asg_agent.records.store import FINDING, REFERENCE_CLEAR
from asg_analysis.campaign_metrics import (
    PAPER,
    PAPER_SCENARIOS,
    _differential,
    _perception_collision,
    _perception_finding,
    _ref,
    active_hours,
    distinct_curve,
    elapsed_hours,
    fmt,
)
from asg_analysis.studies.dynamics import rank_figures


#: The scores of an attributed campaign (issue #25), each counted and counted distinct: (key, label, predicate)
ATTRIBUTED_SCORES = (
    ("perception", f"perception findings (proxy >= {FINDING:g}, reference < {REFERENCE_CLEAR:g})", _perception_finding),
    ("differential", "differential findings (proxy - reference >= 1)", _differential),
    ("collisions", "perception collisions (the reference drove through)", _perception_collision),
)


def attributed_comparison(load, section: dict, out: str):
    """Round 3's search comparison: per arm and seed, each of ATTRIBUTED_SCORES counted and
    counted distinct (threshold_m, in the order found) against scenarios spent and wall time."""
    budget, thr = int(section.get("budget", 1000)), float(section.get("threshold_m", 5.0))
    runs, summary = {}, {}
    for arm, rels in section["arms"].items():
        runs[arm] = []
        for rel in rels:
            camp, rows = load(rel)
            rows = sorted(rows, key=lambda r: r["job"])[:budget]
            r = {
                "seed": camp["seed"],
                "name": camp["name"],
                "scenarios": len(rows),
                "export": rel,
                "hours": elapsed_hours(rows, budget),
                "max_proxy": max((x["proxy"] for x in rows if x["proxy"] is not None), default=None),
                "max_difference": max(
                    (
                        x["proxy"] - _ref(x)["proxy"]
                        for x in rows
                        if x["proxy"] is not None and _ref(x).get("proxy") is not None
                    ),
                    default=None,
                ),
                "attributed": sum(bool(_ref(x)) for x in rows),
            }
            for key, _, pred in ATTRIBUTED_SCORES:
                r[key] = np.cumsum([pred(x) for x in rows]).astype(int)
                r[key + "_distinct"] = distinct_curve(rows, budget, thr, pred=pred)
            runs[arm].append(r)
    full = lambda rs: [r for r in rs if r["scenarios"] >= budget]  # noqa: E731
    md = [
        "",
        f"### Search comparison on the fixed stack (round 3: Exp. 1, flawed U-Net, bf16, every scenario "
        f"attributed; budget {budget} scenarios per run; distinct at {thr:g} m)",
        "",
        "| method | seed | scenarios | "
        + " | ".join(f"{lab}: count / distinct" for _, lab, _ in ATTRIBUTED_SCORES)
        + " | largest proxy | largest difference | wall time | scenarios per hour |",
        "|---|---|---|" + "---|" * len(ATTRIBUTED_SCORES) + "---|---|---|---|",
    ]
    for arm, rs in runs.items():
        summary[arm] = []
        for r in rs:
            h = float(r["hours"][-1]) if r["hours"] is not None else None
            summary[arm].append(
                {
                    "seed": r["seed"],
                    "name": r["name"],
                    "export": r["export"],
                    "scenarios": r["scenarios"],
                    "attributed": r["attributed"],
                    "hours": h,
                    "max_proxy": r["max_proxy"],
                    "max_difference": r["max_difference"],
                    **{k: int(r[k][-1]) for k, _, _ in ATTRIBUTED_SCORES},
                    **{k + "_distinct": int(r[k + "_distinct"][-1]) for k, _, _ in ATTRIBUTED_SCORES},
                }
            )
            md.append(
                f"| {arm} | {r['seed']} | {r['scenarios']}"
                + ("" if r["scenarios"] >= budget else " (running)")
                + " | "
                + " | ".join(f"{int(r[k][-1])} / {int(r[k + '_distinct'][-1])}" for k, _, _ in ATTRIBUTED_SCORES)
                + f" | {fmt(r['max_proxy'])} | {fmt(r['max_difference'], '+.2f')} | "
                + (f"{h * 60:.0f} min | {r['scenarios'] / h:,.0f}" if h else "- | -")
                + " |"
            )
    rnd = full(runs.get("random", []))
    if len(runs) > 1 and rnd:
        md += [
            "",
            "Mean over the seeds that reached the budget (min-max), and the ratio to random search's mean:",
            "",
            "| method | seeds | " + " | ".join(f"{lab}, distinct" for _, lab, _ in ATTRIBUTED_SCORES) + " |",
            "|---|---|" + "---|" * len(ATTRIBUTED_SCORES),
        ]
        for arm, rs in runs.items():
            rs = full(rs)
            if not rs:
                continue
            cells = []
            for k, _, _ in ATTRIBUTED_SCORES:
                v = [int(r[k + "_distinct"][-1]) for r in rs]
                base = np.mean([int(r[k + "_distinct"][-1]) for r in rnd])
                cells.append(
                    f"{np.mean(v):.1f} ({min(v)}-{max(v)})" + (f", {np.mean(v) / base:.2f}x" if base > 0 else "")
                )
            md.append(f"| {arm} | {len(rs)} | " + " | ".join(cells) + " |")
    for measure, xlabel in (("scenarios", "scenarios spent"), ("hours", "wall time [h]")):
        attributed_figure(runs, budget, thr, measure, xlabel, os.path.join(out, f"attributed_{measure}.png"))
    # The first arm's first run: its top two perception-attributable scenarios, as Figures 5-8.
    first = next(iter(section["arms"].values()))[0]
    camp, rows = load(first)
    summary["_ranks"] = rank_figures(
        camp, sorted(rows, key=lambda r: r["job"])[:budget], os.path.join(out, "attributed_rank")
    )
    return summary, md


def attributed_figure(runs, budget, thr, measure, xlabel, out):
    """One panel per score, distinct finds against `measure` (scenarios or hours); an arm of
    several seeds as its mean over the budget with the min-max shaded (against hours: each seed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(ATTRIBUTED_SCORES), figsize=(5.0 * len(ATTRIBUTED_SCORES), 4.0))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, (key, label, _) in zip(axes, ATTRIBUTED_SCORES):
        for k, (arm, rs) in enumerate(runs.items()):
            c = colours[k % len(colours)]
            done = [r for r in rs if r["scenarios"] >= budget]
            if measure == "scenarios" and len(done) > 1:
                a = np.stack([r[key + "_distinct"] for r in done])
                x = np.arange(1, budget + 1)
                ax.plot(x, a.mean(0), color=c, label=f"{arm} (mean of {len(done)} seeds, min-max)")
                ax.fill_between(x, a.min(0), a.max(0), color=c, alpha=0.2)
                continue
            for j, r in enumerate(rs):
                x = np.arange(1, r["scenarios"] + 1) if measure == "scenarios" else r["hours"]
                if x is None:
                    continue
                ax.plot(
                    x,
                    r[key + "_distinct"],
                    color=c,
                    lw=1.2,
                    ls=("-", "--", ":")[j % 3],
                    label=f"{arm} (seed {r['seed']})",
                )
        ax.set_xlabel(xlabel)
        ax.set_ylabel(f"distinct ({thr:g} m)")
        ax.set_title(label, fontsize=9)
        ax.set_ylim(bottom=0, top=max(1.0, ax.get_ylim()[1]))
        ax.yaxis.get_major_locator().set_params(integer=True)
        ax.grid(alpha=0.3)
        if measure == "scenarios":
            ax.set_xlim(0, budget)
    axes[0].legend(fontsize=7)
    fig.suptitle(
        f"Exp. 1, flawed U-Net (bf16), every scenario attributed: distinct perception-attributable finds "
        f"against {xlabel}",
        fontsize=10,
    )
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    plt.close(fig)


def table2_attributed(load, section: dict, out: str):
    """Round 3's Table 2 (issue #25): per experiment one attributed TD3-PER-ASP campaign, its
    counts of proxy >= 3 and >= 4 (each split into the perception's, reference < 2, and the
    stack's, reference >= 3), the largest, per 1,000, perception collisions, beside the paper's
    row; and each campaign's rank-1 and rank-2 perception-attributable scenarios (rank_figures)."""
    summary, md = {}, []
    if not section:
        return summary, md
    md += [
        "",
        "### Table 2 on the fixed stack (round 3: TD3-PER-ASP, flawed U-Net, every scenario attributed)",
        "",
        "| experiment | scenarios | proxy >= 3: all / perception's / stack's | >= 4: all / perception's / stack's "
        "| largest | per 1,000: >= 3 / >= 4 | perception collisions | paper (of 5,000): >= 3 / >= 4 / largest "
        "| paper per 1,000 | wall time |",
        "|" + "---|" * 10,
    ]
    for exp, rel in section.items():
        camp, rows = load(rel)
        c = counts(rows)
        n = c["scenarios"]
        split = {}
        for level in (3.0, 4.0):
            sel = [r for r in rows if r["proxy"] is not None and r["proxy"] >= level]
            refp = [_ref(r).get("proxy") for r in sel]
            split[level] = (
                len(sel),
                sum(q is not None and q < REFERENCE_CLEAR for q in refp),
                sum(q is not None and q >= FINDING for q in refp),
            )
        hours = active_hours(rows)
        p = PAPER.get(exp)
        ranks = rank_figures(camp, rows, os.path.join(out, f"table2_{exp}_rank"))
        summary[exp] = dict(
            c, export=rel, hours=hours, ge3_split=list(split[3.0]), ge4_split=list(split[4.0]), ranks=ranks
        )
        md.append(
            f"| {exp} | {n} | {' / '.join(map(str, split[3.0]))} | {' / '.join(map(str, split[4.0]))} | "
            f"{fmt(c['max_proxy'])} | {1000 * split[3.0][0] / n:.0f} / {1000 * split[4.0][0] / n:.0f} | "
            f"{c.get('perception_collisions', '-')} | "
            + (
                f"{p[0]} / {p[1]} / {p[2]:.2f} | {1000 * p[0] / PAPER_SCENARIOS:.0f} / "
                f"{1000 * p[1] / PAPER_SCENARIOS:.0f}"
                if p
                else "- | -"
            )
            + f" | {fmt(hours * 60 if hours else None, '.0f')} min |"
        )
    md.append("")
    return summary, md


def flaw_or_layout_attributed(load, base: str, section: dict):
    """(summary, table lines) of round 3's flaw or layout: what an attributed campaign blamed on
    the perception (`asg_agent.ros.rerun --select perception`), re-run on other stacks and grids;
    per class of the campaign's verdict, how many fail the same way again, and the collisions
    split by the obstacle the campaign's run hit. section: {file: R.json (rerun summary's; its
    re-runs in the folder R/), campaign: NAME (the heading's), export: the campaign's export}."""
    from asg_agent.scoring.attribution import RERUN_CLASSES as CLASSES, still_failing

    with open(os.path.join(base, section["file"])) as f:
        rows = json.load(f)["summary"]
    hit = {}
    if section.get("export"):
        _, crows = load(section["export"])
        hit = {r["job"]: r["meshes"][r["collision_with"]] for r in crows if r.get("collision_with") is not None}
    folder = os.path.join(base, os.path.splitext(section["file"])[0])
    for s in rows:
        by_mesh = {}
        path = os.path.join(folder, s["file"])
        if hit and os.path.exists(path):
            with open(path) as f:
                for r in (json.loads(line) for line in f if line.strip()):
                    if r.get("campaign_class") == "collision" and r["job"] in hit:
                        e = by_mesh.setdefault(hit[r["job"]], {"runs": 0, "still": 0})
                        e["runs"] += 1
                        e["still"] += still_failing(r)
        s["collisions_by_obstacle"] = by_mesh
    label = {
        "finding": "perception findings: still >= 3",
        "differential": "differential: still >= 1 over the reference",
        "collision": "perception collisions: collides again",
    }
    md = [
        "",
        f"### Flaw or layout, round 3 (what {section.get('campaign', 'the campaign')} blamed on the perception, re-run)",
        "",
        "| planner grid | stack | re-run | "
        + " | ".join(label[c] for c in CLASSES)
        + " | collides again, by the obstacle the campaign's run hit | errors |",
        "|" + "---|" * (5 + len(CLASSES)),
    ]
    for s in sorted(rows, key=lambda s: (s["grid"] != "paper", s["grid"], s["stack"])):
        cells = []
        for c in CLASSES:
            e = (s.get("by_class") or {}).get(c)
            cells.append(f"{e['still']} of {e['runs']}" if e else "-")
        cells.append(
            ", ".join(f"{m} {e['still']} of {e['runs']}" for m, e in sorted(s["collisions_by_obstacle"].items())) or "-"
        )
        md.append(f"| {s['grid']} | {s['stack']} | {s['runs']} | " + " | ".join(cells) + f" | {s['errors']} |")
    return rows, md
