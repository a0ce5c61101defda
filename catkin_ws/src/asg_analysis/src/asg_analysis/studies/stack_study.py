"""The default search against uniform random at equal budget on one stack under test, one seed an
arm or several (issue #39: the depth stack). No ROS.

Endpoint: scenarios whose run fails (attribution.RunOutcome.fails: a collision, a timeout, a flip,
out of bounds, or proxy >= FINDING) per 1,000, with the exact (Clopper-Pearson) 95 % interval of
each arm's rate and Fisher's exact test between arms. One seed an arm makes each arm's count a
binomial draw of its own campaign; it does not sample the spread between seeds, so it can show
that neither arm finds a failure at a rate above the interval's upper end, not that one search
beats another in general. Secondary, descriptive: each arm's proxy distribution (median, 90th
percentile, largest, the share of scenarios at or above CANDIDATE) and the Mann-Whitney U test
of the proxies of the two arms' scenarios.

    python3 -m asg_analysis stack-study results/depth exp1-depth-td3-per-asp-s0 exp1-depth-random-s0 \\
        [--json results/depth/comparison.json] [--markdown]

Several seeds an arm (comma-separated campaign names, one per seed; results/depth/plan-seeds.txt):
the endpoint per seed with its exact interval, and between arms the per-seed rates compared as
the round-4 protocol compares arms (asg_analysis.stats.compare: each arm's mean with a
bootstrap 95 % interval, the ratio of the means, the Mann-Whitney U test of the per-seed rates),
with Fisher's exact test of the pooled counts beside it.

    python3 -m asg_analysis stack-study results/depth \\
        exp1-depth-td3-per-asp-s0,exp1-depth-td3-per-asp-s1,exp1-depth-td3-per-asp-s2 \\
        exp1-depth-random-s0,exp1-depth-random-s1,exp1-depth-random-s2 --json results/depth/seeds.json --markdown
"""

import argparse
import json
import os
import sys
from typing import Dict, List

import numpy as np

from asg_agent.records.export import read_export
from asg_analysis.stats import LEVEL, exact_interval, mann_whitney_scipy
from asg_agent.scoring.attribution import CANDIDATE, RunOutcome
from asg_analysis.files import write_json


def arm(rows: List[dict]) -> Dict:
    """One campaign's endpoint and proxy figures."""
    done = [r for r in rows if not RunOutcome.of(r).error]
    fails = [r for r in done if RunOutcome.of(r).fails]
    proxy = np.array([r["proxy"] for r in done], float)
    lo, hi = exact_interval(len(fails), len(done))
    terms: Dict[str, int] = {}
    for r in rows:
        terms[r["termination"]] = terms.get(r["termination"], 0) + 1
    return {
        "scenarios": len(rows),
        "errors": len(rows) - len(done),
        "failures": len(fails),
        "failure_jobs": [r["job"] for r in fails],
        "per_1000": 1000.0 * len(fails) / len(done),
        "per_1000_interval": [1000.0 * lo, 1000.0 * hi],
        "terminations": dict(sorted(terms.items())),
        "proxy_median": float(np.median(proxy)),
        "proxy_p90": float(np.quantile(proxy, 0.9)),
        "proxy_max": float(proxy.max()),
        "proxy_ge_candidate": int((proxy >= CANDIDATE).sum()),
        "proxies": proxy.tolist(),
    }


def study(folder: str, search: str, baseline: str) -> Dict:
    from scipy.stats import fisher_exact

    arms = {}
    for name in (search, baseline):
        path = os.path.join(folder, f"{name}.jsonl.gz")
        if not os.path.exists(path):
            raise FileNotFoundError(f"{path}: no export (run scripts/repro/campaigns.sh with its plan)")
        _, rows = read_export(path)
        arms[name] = arm(rows)
    a, b = arms[search], arms[baseline]
    table = [[a["failures"], a["scenarios"] - a["errors"] - a["failures"]]]
    table.append([b["failures"], b["scenarios"] - b["errors"] - b["failures"]])
    _, p = fisher_exact(table, alternative="two-sided")
    mw = mann_whitney_scipy(a["proxies"], b["proxies"])  # hundreds of layouts an arm: past the exact test
    for v in arms.values():
        del v["proxies"]
    return {
        "search": search,
        "baseline": baseline,
        "arms": arms,
        "fisher_p": float(p),
        "proxy_mann_whitney": mw,
        "candidate_threshold": CANDIDATE,
        "level": LEVEL,
    }


def arm_name(names: List[str]) -> str:
    """The arm's name: its campaigns' names without their seed suffix (exp1-depth-random-s2)."""
    stems = {n.rsplit("-s", 1)[0] if n.rsplit("-s", 1)[-1].isdigit() else n for n in names}
    return stems.pop() if len(stems) == 1 else "+".join(sorted(stems))


def study_seeds(folder: str, searches: List[str], baselines: List[str]) -> Dict:
    """study() over several seeds an arm: every campaign's figures, and the arms compared on their
    per-seed failures per 1,000 (stats.compare, the search the default), pooled Fisher beside it."""
    from scipy.stats import fisher_exact

    from asg_analysis.stats import compare

    if len(set(searches + baselines)) != len(searches + baselines):
        raise ValueError("a campaign is named twice")
    campaigns, arms = {}, {}
    for names in (searches, baselines):
        for name in names:
            path = os.path.join(folder, f"{name}.jsonl.gz")
            if not os.path.exists(path):
                raise FileNotFoundError(f"{path}: no export (run scripts/repro/campaigns.sh with its plan)")
            campaigns[name] = arm(read_export(path)[1])
            del campaigns[name]["proxies"]
        arms[arm_name(names)] = names
    if len(arms) != 2:
        raise ValueError(f"the search's and the baseline's campaigns share a name: {sorted(arms)}")
    pooled = []
    for names in arms.values():
        fails = sum(campaigns[n]["failures"] for n in names)
        pooled.append([fails, sum(campaigns[n]["scenarios"] - campaigns[n]["errors"] for n in names) - fails])
    rows = compare({a: [campaigns[n]["per_1000"] for n in names] for a, names in arms.items()}, arm_name(searches))
    return {
        "search": arm_name(searches),
        "baseline": arm_name(baselines),
        "arms": arms,
        "campaigns": campaigns,
        "compare": rows,
        "pooled": pooled,
        "pooled_fisher_p": float(fisher_exact(pooled, alternative="two-sided")[1]),
        "level": LEVEL,
    }


def markdown_seeds(s: Dict) -> str:
    from asg_analysis.stats import markdown as compare_table

    head = "| campaign | scenarios | failures | per 1,000 (95 % exact interval) | proxy median / p90 / largest |\n"
    head += "|---|---|---|---|---|\n"
    rows = []
    for names in s["arms"].values():
        for n in names:
            a = s["campaigns"][n]
            lo, hi = a["per_1000_interval"]
            rows.append(
                f"| {n} | {a['scenarios']} | {a['failures']} | {a['per_1000']:.1f} ({lo:.1f}-{hi:.1f}) "
                f"| {a['proxy_median']:.3f} / {a['proxy_p90']:.3f} / {a['proxy_max']:.3f} |\n"
            )
    (f_s, n_s), (f_b, n_b) = s["pooled"]
    tail = (
        f"\nPooled over the seeds: {f_s} failures in {f_s + n_s:,} against {f_b} in {f_b + n_b:,}, "
        f"Fisher's exact test p = {s['pooled_fisher_p']:.3g}.\n"
    )
    return head + "".join(rows) + "\n" + compare_table(s["compare"], "failures") + "\n" + tail


def markdown(s: Dict) -> str:
    head = (
        "| arm | scenarios | failures | per 1,000 (95 % exact interval) | proxy median / p90 / largest "
        f"| proxy >= {s['candidate_threshold']:g} |\n|---|---|---|---|---|---|\n"
    )
    rows = []
    for name, a in s["arms"].items():
        lo, hi = a["per_1000_interval"]
        rows.append(
            f"| {name} | {a['scenarios']} | {a['failures']} | {a['per_1000']:.1f} ({lo:.1f}-{hi:.1f}) "
            f"| {a['proxy_median']:.3f} / {a['proxy_p90']:.3f} / {a['proxy_max']:.3f} | {a['proxy_ge_candidate']} |\n"
        )
    mw = s["proxy_mann_whitney"]
    tail = (
        f"\nFisher's exact test of the failure counts: p = {s['fisher_p']:.3g}. Proxies of the two arms' "
        f"scenarios, Mann-Whitney U: p = {mw['p']:.3g}, rank-biserial effect {mw['effect']:+.3f} "
        f"(+1: every scenario of {s['search']} scores above every one of {s['baseline']}).\n"
    )
    return head + "".join(rows) + tail


def run(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("folder", help="folder of the campaigns' exports (NAME.jsonl.gz)")
    p.add_argument("search", help="the search's campaign name (several seeds: comma-separated)")
    p.add_argument("baseline", help="the baseline's campaign name, uniform random (several seeds: comma-separated)")
    p.add_argument("--json", default="", help="write the figures here")
    p.add_argument("--markdown", action="store_true", help="print the table as docs/your-stack.md shows it")
    a = p.parse_args(argv)
    searches, baselines = a.search.split(","), a.baseline.split(",")
    seeds = len(searches) > 1 or len(baselines) > 1
    try:
        s = study_seeds(a.folder, searches, baselines) if seeds else study(a.folder, a.search, a.baseline)
    except (FileNotFoundError, ValueError) as e:
        print(f"stack_study: {e}", file=sys.stderr)
        return 2
    if a.json:
        write_json(a.json, s)
    print((markdown_seeds(s) if seeds else markdown(s)) if a.markdown else json.dumps(s, indent=1, sort_keys=True))
    return 0
