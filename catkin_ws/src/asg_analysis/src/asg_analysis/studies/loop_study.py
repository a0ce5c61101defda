"""The design loop's measurement (issue #40; docs/design-loop.md section 4), as the protocol
experiments/protocol-design-loop.yaml fixed it before its data. No ROS.

Arms: the default search against `flawed`, the stack hardened on findings and the one hardened on
random scenes, one campaign a seed (results/hardening/plan.txt names them). Endpoint: flaw + model
findings (three-stack attribution) per 1,000 of each campaign's first `budget` scenarios. Per seed
the exact (Clopper-Pearson) 95 % interval; between arms asg_analysis.stats.compare (each arm's
mean with a bootstrap 95 % interval over seeds, the ratio of the means, Mann-Whitney U of the per-seed
rates), the hardened-findings arm the default. The target, judged only once every campaign of the
plan has all its scenarios: hardened-findings <= `ratio_to_flawed` of flawed's mean, its interval
below hardened-random's, and its random-layout baseline (results/baseline/exp1/MODEL.jsonl) no worse
than flawed's in collisions and proxy >= 3.

Round 2 (protocol `round2`, results/hardening/plan-round2.txt): the findings arm hardened again,
searched on its own seeds, compared with round 1's findings arm and with flawed once both rounds are
complete; the reading fixed before the data: "compound" where round 2's mean is below round 1's with
bootstrap intervals apart, "saturate" otherwise.

A campaign whose export is missing or short is listed as not complete; nothing is computed from a
partial export.

    python3 -m asg_analysis loop-study            # rewrites both blocks in docs/design-loop.md
    python3 -m asg_analysis loop-study --check    # exit 1 when a block is stale
    python3 -m asg_analysis loop-study --json results/hardening/loop.json --figure docs/images/design_loop.png
"""

import argparse
import json
import os
import shlex
import sys
from typing import Dict, List, Optional

import yaml

from asg_analysis import stats
from asg_analysis.protocol_analysis import interruptions
from asg_agent.scoring.attribution import FINDING

from asg_agent.paths import REPO
from asg_analysis.files import write_json

PROG = "python3 -m asg_analysis loop-study"

DOC = os.path.join(REPO, "docs", "design-loop.md")
PROTOCOL = os.path.join(REPO, "experiments", "protocol-design-loop.yaml")
FOLDER = os.path.join(REPO, "results", "hardening")
BASELINES = os.path.join(REPO, "results", "baseline", "exp1")
DEFAULT = "hardened-findings"
ROUND2 = "hardened-findings-2"  # the findings arm hardened again (protocol `round2`)
BEGIN, END = "<!-- loop table -->", "<!-- end loop table -->"
BEGIN2, END2 = "<!-- round2 table -->", "<!-- end round2 table -->"


def plan_campaigns(plan: str) -> Dict[tuple, str]:
    """{(model, seed): campaign name} from a plan file (asg_agent.cli.plan's format)."""
    out = {}
    with open(plan, encoding="utf-8") as f:
        for line in f:
            words = shlex.split(line, comments=True)
            if not words:
                continue
            args = dict(w.split(":=", 1) for w in words[3:] if ":=" in w)
            out[(args.get("model"), int(args.get("seed", 0)))] = words[0]
    return out


def campaign_figures(rows: List[dict], budget: int) -> Dict:
    """One campaign's endpoint over its first `budget` scenarios."""
    from asg_analysis.stats import exact_interval

    keep = [r for r in rows if r["job"] < budget]
    flaw = sum(r.get("attribution") == "flaw" for r in keep)
    model = sum(r.get("attribution") == "model" for r in keep)
    lo, hi = exact_interval(flaw + model, len(keep))
    return {
        "scenarios": len(keep),
        "flaw": flaw,
        "model": model,
        "per_1000": 1000.0 * (flaw + model) / len(keep),
        "per_1000_interval": [1000.0 * lo, 1000.0 * hi],
        "collisions": sum(r["termination"] == "COLLISION" for r in keep),
    }


def baseline_counts(model: str, folder: str = BASELINES) -> Optional[Dict]:
    path = os.path.join(folder, f"{model}.jsonl")
    if not os.path.isfile(path):
        return None
    with open(path, encoding="utf-8") as f:
        rows = [json.loads(line) for line in f if line.strip()]
    return {
        "layouts": len(rows),
        "collisions": sum(r["termination"] == "COLLISION" for r in rows),
        "proxy_ge_3": sum(r["proxy"] is not None and r["proxy"] >= FINDING for r in rows),
    }


def judge(per_seed: Dict[str, List[float]], baselines: Dict[str, Optional[Dict]], ratio_to_flawed: float) -> Dict:
    """The comparison and the target, from complete data: per_seed {arm: [findings per 1,000 a seed]}
    (arms flawed, hardened-findings, hardened-random), baselines {arm: baseline_counts or None}."""
    rows = stats.compare(per_seed, DEFAULT)
    by = {r["arm"]: r for r in rows}
    hf, fl, hr = by[DEFAULT], by["flawed"], by["hardened-random"]
    ratio = hf["mean"] / fl["mean"] if fl["mean"] > 0 else float("inf")
    b_hf, b_fl = baselines.get(DEFAULT), baselines.get("flawed")
    baseline_ok = (
        None
        if b_hf is None or b_fl is None
        else b_hf["collisions"] <= b_fl["collisions"] and b_hf["proxy_ge_3"] <= b_fl["proxy_ge_3"]
    )
    target = {
        "ratio_to_flawed": ratio,
        "ratio_met": ratio <= ratio_to_flawed,
        "below_random": hf["hi"] < hr["lo"],
        "baseline_no_worse": baseline_ok,
    }
    target["met"] = bool(target["ratio_met"] and target["below_random"] and baseline_ok)
    # The open question (findings against random scenes): the seeds an arm a protocol would need,
    # from the spread the three seeds show (issue #57; an estimate, not run)
    need = stats.seeds_per_arm(per_seed[DEFAULT], per_seed["hardened-random"])
    return {"compare": rows, "target": target, "open_question": need}


def collect(folder: str, plan: str, arms: Dict[str, str], seeds: List[int], budget: int) -> tuple:
    """(campaigns, per_seed, not_complete) of the plan's campaigns of `arms` {arm: model} x seeds:
    a campaign is counted only when its export holds all its first `budget` scenarios."""
    from asg_agent.records.export import read_export

    names = plan_campaigns(os.path.join(folder, plan))
    campaigns, per_seed, missing = {}, {}, {}
    for arm, model in arms.items():
        for seed in seeds:
            name = names.get((model, seed))
            if name is None:
                raise ValueError(f"{folder}/{plan} has no campaign of model {model} seed {seed}")
            path = os.path.join(folder, f"{name}.jsonl.gz")
            camp, rows = read_export(path) if os.path.isfile(path) else ({}, [])
            # every resume, restart and long pause (issue #57; the flaw study's rule, one place)
            settings = (camp.get("settings") if isinstance(camp, dict) else None) or "{}"
            stops = interruptions(json.loads(settings) if isinstance(settings, str) else settings, rows)
            if len({r["job"] for r in rows if r["job"] < budget}) < budget:
                missing[name] = {"arm": arm, "seed": seed, "interruptions": stops}
                continue
            campaigns[name] = dict(arm=arm, seed=seed, interruptions=stops, **campaign_figures(rows, budget))
            per_seed.setdefault(arm, []).append(campaigns[name]["per_1000"])
    return campaigns, per_seed, missing


def read_round2(
    r1: Dict[str, List[float]], r1_missing: Dict, r2: Dict[str, List[float]], r2_missing: Dict
) -> Optional[Dict]:
    """Round 2's comparison and reading (protocol `round2.reading`), from complete data only: the
    findings arm of round 2 against round 1's and against flawed; "compound" where round 2's mean is
    below round 1's with bootstrap intervals apart, "saturate" otherwise."""
    if r1_missing or r2_missing:
        return None
    rows = stats.compare({ROUND2: r2[ROUND2], DEFAULT: r1[DEFAULT], "flawed": r1["flawed"]}, ROUND2)
    by = {r["arm"]: r for r in rows}
    # an interval entirely below round 1's puts the mean below it too
    compound = by[ROUND2]["hi"] < by[DEFAULT]["lo"]
    return {"compare": rows, "reading": "compound" if compound else "saturate"}


def study(folder: str = FOLDER, protocol: str = PROTOCOL, baselines: str = BASELINES) -> Dict:
    with open(protocol, encoding="utf-8") as f:
        proto = yaml.safe_load(f)
    budget, seeds = int(proto["budget"]), [int(s) for s in proto["seeds"]]
    arms = {a: v["model"] for a, v in proto["arms"].items() if a != "full"}
    campaigns, per_seed, missing = collect(folder, "plan.txt", arms, seeds, budget)
    out = {
        "protocol": os.path.relpath(protocol, REPO),
        "budget": budget,
        "seeds": seeds,
        "campaigns": campaigns,
        "not_complete": missing,
        "baselines": {a: baseline_counts(m, baselines) for a, m in arms.items()},
    }
    if not missing:
        out.update(judge(per_seed, out["baselines"], float(proto["target"]["ratio_to_flawed"])))
    r2 = proto.get("round2")
    if r2 and os.path.isfile(os.path.join(folder, "plan-round2.txt")):
        c2 = r2["campaigns"]
        b2, s2 = int(c2["budget"]), [int(s) for s in c2["seeds"]]
        camp2, per2, miss2 = collect(folder, "plan-round2.txt", {ROUND2: r2["models"]["findings"]}, s2, b2)
        out["round2"] = {"budget": b2, "seeds": s2, "campaigns": camp2, "not_complete": miss2}
        got = read_round2(per_seed, missing, per2, miss2)
        if got:
            out["round2"].update(got)
    return out


def campaign_rows(s: Dict) -> List[str]:
    out = [
        "| campaign | arm | seed | scenarios | flaw | model | flaw + model per 1,000 (95 % exact interval) | collisions |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for name, c in s["campaigns"].items():
        lo, hi = c["per_1000_interval"]
        out.append(
            f"| {name} | {c['arm']} | {c['seed']} | {c['scenarios']} | {c['flaw']} | {c['model']} | "
            f"{c['per_1000']:.1f} ({lo:.1f}-{hi:.1f}) | {c['collisions']} |"
        )
    for name, c in s["not_complete"].items():
        out.append(f"| {name} | {c['arm']} | {c['seed']} | not complete | | | | |")
    devs = [(n, d) for n, c in {**s["campaigns"], **s["not_complete"]}.items() for d in c.get("interruptions", [])]
    out += [
        "",
        "Deviations (every resume, restart or pause over 10 minutes of these campaigns, from their exports): "
        + ("; ".join(f"{n}: {d}" for n, d in devs) if devs else "none")
        + ".",
    ]
    return out


def markdown(s: Dict) -> str:
    out = campaign_rows(s)
    out.append("")
    if "compare" not in s:
        n = len(s["not_complete"])
        out.append(
            f"{n} of {n + len(s['campaigns'])} campaigns not complete: the comparison between arms and the "
            "target are computed when every campaign of the plan has all its scenarios."
        )
        return "\n".join(out)
    out.append(stats.markdown(s["compare"], stats.SCORES["findings"][0]))
    t = s["target"]
    out += [
        "",
        f"Target: hardened-findings / flawed = {t['ratio_to_flawed']:.2f} "
        f"({'met' if t['ratio_met'] else 'missed'}, <= 0.5); its interval "
        f"{'below' if t['below_random'] else 'not below'} hardened-random's; its baseline "
        + {True: "no worse than", False: "worse than", None: "not measured against"}[t["baseline_no_worse"]]
        + f" flawed's. Overall: **{'met' if t['met'] else 'missed'}**.",
    ]
    return "\n".join(out)


def markdown_round2(s: Dict) -> str:
    """Round 2's block: its campaigns, then (all of both rounds complete) the comparison and reading."""
    r2 = s.get("round2")
    if r2 is None:
        return "Round 2 is not in the protocol or has no plan."
    out = campaign_rows(r2) + [""]
    if "compare" not in r2:
        n1, n2 = len(s["not_complete"]), len(r2["not_complete"])
        out.append(
            f"{n2} of {n2 + len(r2['campaigns'])} round-2 campaigns not complete"
            + (f" (and {n1} of round 1's)" if n1 else "")
            + ": round 2 is compared with round 1 when every campaign of both plans has all its scenarios."
        )
        return "\n".join(out)
    out.append(stats.markdown(r2["compare"], stats.SCORES["findings"][0]))
    out += [
        "",
        f"Reading (fixed before the data): **{r2['reading']}** (compound: round 2's mean below round 1's "
        "with intervals apart; saturate: otherwise).",
    ]
    return "\n".join(out)


ARM_COLOURS = {
    "flawed": "tab:red",
    "hardened-findings": "tab:blue",
    "hardened-random": "tab:green",
    ROUND2: "tab:purple",
}


def figure(s: Dict, out: str) -> None:
    """Each complete campaign's flaw + model findings per 1,000 with its exact interval, grouped by
    arm; where every campaign is complete, each arm's mean with its bootstrap interval beside."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    r2 = s.get("round2", {})
    campaigns = {**s["campaigns"], **r2.get("campaigns", {})}
    means = {r["arm"]: r for r in s.get("compare", [])}
    means.update({r["arm"]: r for r in r2.get("compare", []) if r["arm"] == ROUND2})
    arms = [a for a in ARM_COLOURS if any(c["arm"] == a for c in campaigns.values())]
    fig, ax = plt.subplots(figsize=(6.4, 3.6))
    for i, arm in enumerate(arms):
        cs = sorted((c for c in campaigns.values() if c["arm"] == arm), key=lambda c: c["seed"])
        for j, c in enumerate(cs):
            x = i + (j - (len(cs) - 1) / 2) * 0.15
            lo, hi = c["per_1000_interval"]
            ax.errorbar(
                x,
                c["per_1000"],
                yerr=[[c["per_1000"] - lo], [hi - c["per_1000"]]],
                fmt="o",
                capsize=3,
                color=ARM_COLOURS[arm],
            )
            ax.annotate(f"s{c['seed']}", (x, hi), ha="center", va="bottom", fontsize=7)
        row = means.get(arm)
        if row:
            ax.hlines(row["mean"], i - 0.35, i + 0.35, color=ARM_COLOURS[arm])
            ax.fill_between([i - 0.35, i + 0.35], row["lo"], row["hi"], color=ARM_COLOURS[arm], alpha=0.15, lw=0)
    ax.set_xticks(range(len(arms)), [a.replace("-", "\n", 1) for a in arms])  # two lines: four arms fit
    ax.set_xlim(-0.6, len(arms) - 0.4)
    ax.set_ylim(bottom=0)
    ax.set_ylabel("flaw + model findings per 1,000")
    left = len(s["not_complete"]) + len(r2.get("not_complete", {}))
    ax.set_title(
        f"Default search, {s['budget']} scenarios a seed (dots: seeds, exact 95 % intervals)"
        + (f"\n{left} campaign(s) of the plans not complete, not drawn" if left else ""),
        fontsize=9,
    )
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    plt.close(fig)


def run(argv=None) -> int:
    p = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    p.add_argument("--check", action="store_true", help="exit 1 when a block of docs/design-loop.md is stale")
    p.add_argument("--json", default="", help="also write the figures here")
    p.add_argument("--figure", default="", help="also draw the per-seed rates here (PNG)")
    a = p.parse_args(argv)
    try:
        s = study()
    except (OSError, ValueError, KeyError) as e:
        print(f"loop_study: {e}", file=sys.stderr)
        return 2
    if a.json:
        write_json(a.json, s)
    if a.figure:
        figure(s, a.figure)
    from asg_analysis.docblocks import rewrite_between as rewrite_block

    rc = rewrite_block(DOC, BEGIN, END, f"{BEGIN}\n{markdown(s)}\n{END}", a.check, "loop_study")
    return max(rc, rewrite_block(DOC, BEGIN2, END2, f"{BEGIN2}\n{markdown_round2(s)}\n{END2}", a.check, "loop_study"))
