"""Every table and figure of docs/experiments.md, recomputed from the compact campaign exports
and re-run results under results/ (no simulation, no ROS; well under a minute).

    python3 -m asg_analysis experiments [--manifest results/experiments.yaml] [--out docs/experiments]

The manifest names which export serves which table (paths relative to the manifest):

    attributed: {budget: 1000, threshold_m: 5.0, arms: {td3-per-asp: [A, B], random: [...], ...}}
                                                         # round 3: searches on the fixed stack, every
                                                         # scenario attributed (scored by ATTRIBUTED_SCORES)
    table2_attributed: {exp1: comparison/A.jsonl.gz, ...}  # round 3's Table 2: an attributed
                                                         # TD3-PER-ASP campaign per experiment
    weather: {exports: [W.jsonl.gz], attributes: [fog_visibility_m, cloud_cover], bins: 4}
                                                         # issue #27: findings by textural attribute
    conditions: {stack: S, layouts: 300, rows: {LABEL: {experiment: E.yaml, stack: S.jsonl,
                 ground_truth: G.jsonl}}}                # issue #27: paired baselines by condition
    table2: {exp1: campaigns/A.jsonl.gz, ...}            # TD3-PER-ASP campaign per experiment
    comparison: {budget: 1000, arms: {td3-per-asp: [A, B, C], random: [...], ...}}
    diversity: {arms: [td3-per-asp, random], top: 100, threshold_m: 5.0, all_thresholds_m: [2, 5, 10]}
    flaw_or_layout_attributed: {file: R.json, campaign: NAME, export: comparison/A.jsonl.gz}
                                                         # round 3: `rerun --select perception`
    differentials: [{export: comparison/D.jsonl.gz, under_test: flawed U-Net, reference: ground truth,
                     figures: diff_gt}]                  # round 3's differential campaigns
    flaw_or_layout: flaw_or_layout.json                  # from `asg_agent.ros.rerun` (optional)
    differential: {export: campaigns/D.jsonl.gz, under_test: flawed U-Net, reference: full U-Net}
                                                         # a --reference-workers campaign (optional)

Writes OUT/tables.md (the tables, quoted in docs/experiments.md), OUT/attributed_{scenarios,hours}.png,
OUT/search_comparison.png,
OUT/top_EXP.png, OUT/differential_{top,curve}.png and OUT/summary.json (every count, read back by the tests).
"""

import argparse
import json
import os
import sys
from typing import Dict

import numpy as np
import yaml

from asg_agent.records.export import counts, read_export
from asg_agent.paths import REPO
from asg_agent.records.store import FINDING
from asg_analysis.campaign_metrics import (
    PAPER,
    PAPER_SCENARIOS,
    active_hours,
    distinct,
    distinct_curve,
    fmt,
    ge3_curve,
)  # noqa: F401
from asg_analysis.studies.attributed_tables import (
    attributed_comparison,
    flaw_or_layout_attributed,
    table2_attributed,
)  # noqa: F401
from asg_analysis.studies.condition_tables import condition_table, weather_tables  # noqa: F401
from asg_analysis.studies.dynamics import comparison_figure, dynamics, rank_figures, top_figure  # noqa: F401
from asg_analysis.studies.differential import (
    differential_section,
)  # noqa: F401

PROG = "python3 -m asg_analysis experiments"


def table2_section(man, load, summary, out):
    """Table 2: each experiment's campaign against the paper's counts (and its top scenario's figure)."""
    md = []
    if man.get("table2"):
        md += [
            "### Table 2",
            "",
            "| experiment | scenarios | proxy >= 3 | >= 4 | largest | per 1,000: >= 3 / >= 4 "
            "| paper (of 5,000): >= 3 / >= 4 / largest | paper per 1,000 | wall time | workers |",
            "|" + "---|" * 10,
        ]
    for exp, rel in (man.get("table2") or {}).items():
        camp, rows = load(rel)
        c = counts(rows)
        hours = active_hours(rows)
        workers = len(json.loads(camp["settings"]).get("workers", [])) if camp.get("settings") else None
        p = PAPER.get(exp)
        summary["table2"][exp] = dict(c, export=rel, hours=hours)
        n = c["scenarios"]
        md.append(
            f"| {exp} | {n} | {c['proxy_ge_3']} | {c['proxy_ge_4']} | {fmt(c['max_proxy'])} | "
            f"{1000 * c['proxy_ge_3'] / n:.0f} / {1000 * c['proxy_ge_4'] / n:.0f} | "
            + (
                f"{p[0]} / {p[1]} / {p[2]:.2f} | {1000 * p[0] / PAPER_SCENARIOS:.0f} / "
                f"{1000 * p[1] / PAPER_SCENARIOS:.0f}"
                if p
                else "- | -"
            )
            + f" | {fmt(hours * 60 if hours else None, '.0f')} min | {workers or '-'} |"
        )
        summary["table2"][exp]["top"] = top_figure(camp, rows, os.path.join(out, f"top_{exp}.png"))
    return md


def comparison_section(man, load, summary, out):
    """The search comparison at the budget, its figure and every run's dynamics; (lines, curves)."""
    md = []
    comp = man.get("comparison") or {}
    budget = int(comp.get("budget", 1000))
    thr = float((man.get("diversity") or {}).get("threshold_m", 5.0))
    curves = {}
    if comp.get("arms"):
        md += [
            "",
            f"### Search comparison (Exp. 1, flawed U-Net, budget {budget} scenarios per run)",
            "",
            "| method | runs (seeds) | proxy >= 3 at the budget: each run | mean | min-max | vs random (mean) "
            f"| of which in scenarios {budget // 2 + 1}-{budget}: each run "
            f"| distinct layouts among them ({thr:g} m, in the order found): each run | mean |",
            "|---|---|---|---|---|---|---|---|---|",
        ]
        for arm, rels in comp["arms"].items():
            curves[arm] = []
            for rel in rels:
                camp, rows = load(rel)
                cv = ge3_curve(rows, budget)
                curves[arm].append(
                    {
                        "seed": camp["seed"],
                        "scenarios": len(cv),
                        "curve": cv,
                        "distinct": distinct_curve(rows, budget, thr),
                    }
                )
        rnd = [c["curve"][-1] for c in curves.get("random", []) if c["scenarios"] >= budget]
        rnd_mean = float(np.mean(rnd)) if rnd else None
        for arm, runs in curves.items():
            full = [int(r["curve"][-1]) for r in runs if r["scenarios"] >= budget]
            short = [
                f"{int(r['curve'][-1])} (s{r['seed']}, only {r['scenarios']})" for r in runs if r["scenarios"] < budget
            ]
            mean = float(np.mean(full)) if full else None
            summary["comparison"][arm] = {
                "runs": [
                    {
                        "seed": r["seed"],
                        "scenarios": r["scenarios"],
                        "ge3": int(r["curve"][-1]),
                        "distinct_ge3": int(r["distinct"][-1]),
                        "ge3_second_half": (
                            int(r["curve"][-1] - r["curve"][budget // 2 - 1]) if r["scenarios"] >= budget else None
                        ),
                    }
                    for r in runs
                ],
                "mean_at_budget": mean,
            }
            md.append(
                f"| {arm} | {len(full)} ({', '.join(str(r['seed']) for r in runs)}) | "
                f"{', '.join(str(v) for v in full + short)} | {fmt(mean, '.1f')} | "
                + (f"{min(full)}-{max(full)}" if full else "-")
                + " | "
                + (f"{mean / rnd_mean:.2f}x" if mean is not None and rnd_mean else "-")
                + " | "
                + ", ".join(
                    str(int(r["curve"][-1] - r["curve"][budget // 2 - 1])) for r in runs if r["scenarios"] >= budget
                )
                + " | "
                + ", ".join(str(int(r["distinct"][-1])) for r in runs)
                + " | "
                + fmt(np.mean([r["distinct"][-1] for r in runs if r["scenarios"] >= budget]) if full else None, ".1f")
                + " |"
            )
        comparison_figure(curves, budget, thr, os.path.join(out, "search_comparison.png"))
        # Where every run placed its obstacles as it went (the summary keeps each arm's first).
        dyn = {}
        for arm, rels in comp["arms"].items():
            for k, rel in enumerate(rels):
                camp, rows = load(rel)
                dyn[(arm, k)] = (camp["name"], dynamics(camp, rows, budget))
        summary["dynamics"] = {arm: d for (arm, k), (_, d) in dyn.items() if k == 0}
        names = list(dyn)
        md += [
            "",
            "### Search dynamics (every run, per 100 scenarios: proxy >= 3 / obstacles "
            "within 2 m of the edge / median distance of obstacles from the start-goal line)",
            "",
            "| scenarios | " + " | ".join(f"{dyn[a][0]}" for a in names) + " |",
            "|---|" + "---|" * len(names),
        ]
        for k in range(max(len(d) for _, d in dyn.values())):
            cells = []
            for a in names:
                d = dyn[a][1]
                cells.append(
                    f"{d[k]['ge3']} / {100 * d[k]['at_edge']:.0f}% / {d[k]['median_to_route_m']:.1f} m"
                    + ("" if d[k]["to"] - d[k]["from"] == 99 else f" (of {d[k]['to'] - d[k]['from'] + 1})")
                    if k < len(d)
                    else "-"
                )
            md.append(f"| {k * 100 + 1}-{(k + 1) * 100} | " + " | ".join(cells) + " |")
    return md, curves


def diversity_section(man, load, summary, curves):
    """Distinct layouts among each arm's findings."""
    md = []
    comp = man.get("comparison") or {}
    budget = int(comp.get("budget", 1000))
    div = man.get("diversity") or {}
    if div.get("arms") and curves:
        top, thr = int(div.get("top", 100)), float(div.get("threshold_m", 5.0))
        thrs = [float(t) for t in div.get("all_thresholds_m", [thr])]
        md += [
            "",
            "### Diversity (a layout is distinct when its mean matched displacement from every higher-ranked "
            "distinct one exceeds the threshold)",
            "",
            "| method | run | distinct among the top %d at %g m | of which proxy >= 3 | proxy >= 3 in all "
            "| distinct among all with proxy >= 3, at %s m |" % (top, thr, " / ".join(f"{t:g}" for t in thrs)),
            "|---|---|---|---|---|---|",
        ]
        for arm in div["arms"]:
            for rel in (comp["arms"].get(arm) or [])[:1]:
                camp, rows = load(rel)
                rows = sorted(rows, key=lambda r: r["job"])[:budget]
                n = distinct(rows, top, thr)
                ge3 = sum((r["proxy"] or 0) >= FINDING for r in rows)
                n3 = {f"{t:g}": distinct(rows, None, t, min_proxy=FINDING) for t in thrs}
                summary["diversity"][arm] = {
                    "export": rel,
                    "distinct": n,
                    "top": min(top, len(rows)),
                    "ge3": ge3,
                    "distinct_ge3": n3,
                }
                md.append(
                    f"| {arm} | {camp['name']} | {n} | {min(top, ge3)} | {ge3} | "
                    + " / ".join(str(v) for v in n3.values())
                    + " |"
                )
    return md


def flaw_or_layout_section(man, base, summary):
    """The top scenarios of the Exp. 1 campaign re-run on other stacks and grids."""
    md = []
    if man.get("flaw_or_layout") and os.path.exists(os.path.join(base, man["flaw_or_layout"])):
        with open(os.path.join(base, man["flaw_or_layout"])) as f:
            fol = json.load(f)
        summary["flaw_or_layout"] = fol["summary"]
        md += [
            "",
            "### Flaw or layout (the top scenarios of the Exp. 1 campaign, re-run)",
            "",
            "| planner grid | stack | re-run | still >= 3 | dropped below 3 | median proxy (campaign's: flawed, paper grid) |",
            "|---|---|---|---|---|---|",
        ]
        for s in fol["summary"]:
            md.append(
                f"| {s['grid']} | {s['stack']} | {s['runs']} | {s['still_ge3']} | {s['dropped']} | "
                f"{fmt(s.get('median_proxy'))} ({fmt(s.get('campaign_median_proxy'))}) |"
            )
    return md


def compute(manifest_path: str, out: str) -> dict:
    base = os.path.dirname(os.path.abspath(manifest_path))
    with open(manifest_path) as f:
        man = yaml.safe_load(f) or {}
    os.makedirs(out, exist_ok=True)
    cache: Dict[str, tuple] = {}

    def load(rel):
        if rel not in cache:
            cache[rel] = read_export(os.path.join(base, rel))
        return cache[rel]

    summary, md = {"table2": {}, "comparison": {}, "diversity": {}}, []
    # -- round 3: searches on the fixed stack, attributed ------------------------------------------
    if (man.get("attributed") or {}).get("arms"):
        summary["attributed"], lines = attributed_comparison(load, man["attributed"], out)
        md += lines[1:]
    if man.get("table2_attributed"):
        summary["table2_attributed"], lines = table2_attributed(load, man["table2_attributed"], out)
        md += lines
    if (man.get("weather") or {}).get("exports"):
        summary["weather"], lines = weather_tables(load, man["weather"], out)
        md += lines[1:]
    if (man.get("terrain") or {}).get("exports"):
        summary["terrain"], lines = weather_tables(load, man["terrain"], out, "terrain and weather", "terrain.png")
        md += lines[1:]
    if (man.get("conditions") or {}).get("rows"):
        summary["conditions"], lines = condition_table(base, man["conditions"], out)
        md += lines
    if (man.get("flaw_or_layout_attributed") or {}).get("file"):
        summary["flaw_or_layout_attributed"], lines = flaw_or_layout_attributed(
            load, base, man["flaw_or_layout_attributed"]
        )
        md += lines
    for spec in man.get("differentials") or []:
        prefix = spec.get("figures") or os.path.basename(spec["export"]).split(".")[0]
        summary.setdefault("differentials", {})[prefix], lines = differential_section(load, spec, out, prefix)
        md += lines
    if man.get("attributed") or man.get("weather") or man.get("terrain"):
        md += ["", "## Round 2 (the stiff follower; stale, kept for the record)", ""]
    md += table2_section(man, load, summary, out)
    lines, curves = comparison_section(man, load, summary, out)
    md += lines
    md += diversity_section(man, load, summary, curves)
    md += flaw_or_layout_section(man, base, summary)
    if man.get("differential"):
        summary["differential"], lines = differential_section(load, man["differential"], out, "differential")
        md += lines
    with open(os.path.join(out, "tables.md"), "w") as f:
        f.write("<!-- generated by `python3 -m asg_analysis experiments`; do not edit -->\n" + "\n".join(md) + "\n")
    with open(os.path.join(out, "summary.json"), "w") as f:
        json.dump(summary, f, indent=1, sort_keys=True)
    return summary


BEGIN, END = "<!-- tables:begin -->", "<!-- tables:end -->"


def docs_block(text: str) -> str:
    """The generated tables as docs/experiments.md quotes them."""
    if BEGIN not in text or END not in text:
        raise ValueError(f"no {BEGIN} ... {END} block")
    return text.split(BEGIN, 1)[1].split(END, 1)[0].strip("\n")


def update_docs(path: str, tables: str):
    with open(path) as f:
        text = f.read()
    docs_block(text)
    head, rest = text.split(BEGIN, 1)
    with open(path, "w") as f:
        f.write(head + BEGIN + "\n" + tables.strip("\n") + "\n" + END + rest.split(END, 1)[1])


def _check(manifest: str, docs: str) -> int:
    """0 when the page's tables block is what `run` writes from the manifest's exports, else 1."""
    import tempfile

    with tempfile.TemporaryDirectory() as out:
        try:
            compute(manifest, out)
            with open(os.path.join(out, "tables.md")) as f:
                tables = f.read()
            with open(docs) as f:
                said = docs_block(f.read())
        except (OSError, ValueError, KeyError) as e:
            print(f"experiments: {e}", file=sys.stderr)
            return 2
    if said.strip("\n") != tables.strip("\n"):
        print(f"experiments: {docs}: the tables block is stale", file=sys.stderr)
        return 1
    return 0


def run(argv=None):
    p = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    p.add_argument("--manifest", default=os.path.join(REPO, "results", "experiments.yaml"))
    p.add_argument("--out", default=os.path.join(REPO, "docs", "experiments"))
    p.add_argument(
        "--docs",
        default=os.path.join(REPO, "docs", "studies", "2026-11-22-paper-table2.md"),
        help="rewrite the block between the tables markers of this file ('' to leave it)",
    )
    p.add_argument(
        "--check", action="store_true", help="write nothing; exit 1 when the --docs block is not what the exports give"
    )
    a = p.parse_args(argv)
    if a.check:
        return _check(a.manifest, a.docs)
    try:
        compute(a.manifest, a.out)
    except (OSError, ValueError, KeyError) as e:
        print(f"experiments: {e}", file=sys.stderr)
        return 2
    with open(os.path.join(a.out, "tables.md")) as f:
        tables = f.read()
    print(tables)
    if a.docs and os.path.exists(a.docs):
        update_docs(a.docs, tables)
    print(f"written: {a.out}/tables.md, summary.json and figures", file=sys.stderr)
    return 0
