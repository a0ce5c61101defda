"""What a campaign's failures have in common (issue #78): rules over the scene's generic
attributes, learnt from the campaign's own results, and their check on fresh samples. No ROS.

    python3 -m asg_analysis rules learn EXPORT.jsonl.gz [EXPORT ...] [--out rules.json]
    python3 -m asg_analysis rules learn --store STORE [--campaign NAME] [--out rules.json]
    python3 -m asg_analysis rules check rules.json RULE_EXPORT.jsonl.gz [...] --base BASE_EXPORT.jsonl.gz [...]

`learn` fits a shallow decision tree (scikit-learn, depth DEPTH, leaves of at least MIN_LEAF
scenarios) that tells the campaign's findings from its other scenarios over the features the
surrogate searches use (asg_agent.search.surrogate.ObstacleFeatures: per class of the scenario,
how many of its obstacles stand in each cell along and beside the route and how close their
shadows come to it, and the free textural values), and writes every leaf whose share of findings
is at least twice the campaign's as a rule: the conditions on its path, its precision and support
in the campaign, and its share of the campaign's findings and distinct findings. A rule says where
the campaign found its failures; it is "learned" only once it holds on fresh samples.

`check` reads the campaigns of `rule-sampler` (uniform layouts that satisfy the rule, as many as
the protocol asks, at least 100) and of `random` in the same experiment (the same sampler without
the rule): the rule's precision on fresh samples against the base rate, each with its exact
(Clopper-Pearson) 95 % interval, their ratio, and Fisher's exact test.
"""

import argparse
import json
import sys
from typing import Dict, List, Optional

import numpy as np

from asg_agent.scoring.places import PRIMARY_RADIUS_M, distinct_flags, place_of_row

PROG = "python3 -m asg_analysis rules"

DEPTH = 3  # [-] the tree's depth: rules of at most three conditions
MIN_LEAF = 10  # [scenarios] the smallest leaf
LIFT = 2.0  # [-] a leaf is a rule when its share of distinct findings is at least this times the campaign's
MIN_DISTINCT = 3  # [-] and it holds at least this many distinct findings


def is_finding(row: dict, target: Optional[str]) -> bool:
    """A finding of class `target` (three-stack attribution's `flaw`, a pair's `regression`), or,
    with target None, a run of the stack under test that failed (not SUCCESS, not ERROR)."""
    if target:
        return row.get("attribution") == target
    return row["termination"] not in ("SUCCESS", "ERROR")


def features(rows: List[dict], experiment) -> tuple:
    """(X, names) of export rows: ObstacleFeatures of their positions and free textural values."""
    from asg_agent.search.surrogate import ObstacleFeatures

    f = ObstacleFeatures(experiment)
    xy = np.asarray([r["positions"] for r in rows], float).reshape(len(rows), -1, 2)
    extra = None
    if f.extra:
        tex = [(k, lo, hi) for k, lo, hi in experiment.textural_free]
        extra = np.zeros((len(rows), f.extra))
        for i, r in enumerate(rows):
            for k, (key, lo, hi) in enumerate(tex):
                extra[i, k] = (float(r["textural"][key]) - lo) / max(hi - lo, 1e-12) * 2.0 - 1.0
    return f.of_positions(xy, extra), f.names()


def _leaves(tree, names) -> List[tuple]:
    """(leaf, [(feature, at_least, threshold), ...]) for every leaf of a fitted tree."""
    t, out = tree.tree_, []

    def walk(node, path):
        if t.children_left[node] == -1:
            out.append((node, path))
            return
        name, thr = names[t.feature[node]], float(t.threshold[node])
        # counts are whole numbers: x <= 1.5 is x < 2; a textural value keeps the tree's cut
        cut = float(np.floor(thr) + 1.0) if thr != np.floor(thr) and not name.startswith("action[") else thr
        walk(t.children_left[node], path + [(name, False, cut)])
        walk(t.children_right[node], path + [(name, True, cut)])

    walk(0, [])
    return out


def learn(rows: List[dict], experiment, target: Optional[str] = "flaw", depth: int = DEPTH) -> Dict:
    """The rules of a campaign's rows (see the module's text), best precision first."""
    from sklearn.tree import DecisionTreeClassifier

    from asg_agent.search.rules import Condition, Rule
    from asg_agent.search.surrogate import ObstacleFeatures

    rows = sorted((r for r in rows if r["termination"] != "ERROR"), key=lambda r: (r.get("_campaign", ""), r["job"]))
    X, names = features(rows, experiment)
    y = np.array([is_finding(r, target) for r in rows])
    # A failure found twice is one failure: the tree sees the first finding of each distinct place
    # (and every other scenario), so that a place found a hundred times weighs as one.
    first = np.zeros(len(rows), bool)
    for camp in sorted({r.get("_campaign", "") for r in rows}):
        idx = [i for i in range(len(rows)) if y[i] and rows[i].get("_campaign", "") == camp]
        for i, new in zip(idx, distinct_flags([place_of_row(rows[i]) for i in idx], PRIMARY_RADIUS_M)):
            first[i] = new
    keep = ~y | first
    base = float(first.sum() / max(1, keep.sum()))
    out = {
        "campaigns": sorted({r.get("_campaign", "") for r in rows}),
        "scenarios": len(rows),
        "findings": int(y.sum()),
        "distinct": int(first.sum()),
        "base_rate": base,
        "target": target,
        "rules": [],
    }
    if first.sum() == 0 or not (~y).any():
        return out
    tree = DecisionTreeClassifier(max_depth=depth, min_samples_leaf=MIN_LEAF, random_state=0)
    tree.fit(X[keep], first[keep])
    for leaf, path in _leaves(tree, names):
        rule = Rule(tuple(Condition(*c) for c in _simplify(path)))
        inside = rule.holds(X, names)
        hits = int((inside & first).sum())
        precision = hits / max(1, int((inside & keep).sum()))
        if hits < MIN_DISTINCT or precision < LIFT * base:
            continue
        out["rules"].append(
            {
                "rule": rule.to_dict(),
                "text": rule.text(),
                "words": rule.words(tuple(ObstacleFeatures(experiment).edges)),
                "support": int((inside & keep).sum()),
                "distinct": hits,
                "precision": precision,
                "lift": precision / base,
                "share_of_distinct": hits / int(first.sum()),
                "share_of_findings": int((inside & y).sum()) / int(y.sum()),
                "example": {
                    "campaign": rows[int(np.flatnonzero(inside & first)[0])].get("_campaign", ""),
                    "job": int(rows[int(np.flatnonzero(inside & first)[0])]["job"]),
                },
            }
        )
    out["rules"].sort(key=lambda r: (-r["precision"], -r["distinct"]))
    return out


def _simplify(path):
    """One condition per feature and direction: the tightest."""
    best = {}
    for name, at_least, cut in path:
        key = (name, at_least)
        if key not in best:
            best[key] = cut
        else:
            best[key] = max(best[key], cut) if at_least else min(best[key], cut)
    return [(n, a, c) for (n, a), c in best.items()]


def clopper_pearson(k: int, n: int, level: float = 0.95) -> tuple:
    from scipy.stats import beta

    a = (1.0 - level) / 2.0
    lo = 0.0 if k == 0 else float(beta.ppf(a, k, n - k + 1))
    hi = 1.0 if k == n else float(beta.ppf(1.0 - a, k + 1, n - k))
    return lo, hi


def check(rule_rows: List[dict], base_rows: List[dict], target: Optional[str] = "flaw") -> Dict:
    """A rule on fresh samples: its precision against the base rate (see the module's text)."""
    from scipy.stats import fisher_exact

    def rate(rows):
        rows = [r for r in rows if r["termination"] != "ERROR"]
        k = sum(is_finding(r, target) for r in rows)
        return k, len(rows)

    k1, n1 = rate(rule_rows)
    k0, n0 = rate(base_rows)
    p = float(fisher_exact([[k1, n1 - k1], [k0, n0 - k0]], alternative="two-sided")[1]) if n1 and n0 else None
    prec, base = k1 / max(1, n1), k0 / max(1, n0)
    return {
        "rule_findings": k1,
        "rule_scenarios": n1,
        "precision": prec,
        "precision_ci": clopper_pearson(k1, n1) if n1 else None,
        "base_findings": k0,
        "base_scenarios": n0,
        "base_rate": base,
        "base_ci": clopper_pearson(k0, n0) if n0 else None,
        "ratio": prec / base if base > 0 else float("inf") if prec > 0 else float("nan"),
        "fisher_p": p,
    }


#: the terms of a rule in words, said once above the rules
TERMS = (
    "  (the route: the straight line from start to goal; its quarters: of its length from the start; "
    "a distance: an obstacle's from that line [m]; a shadow: the obstacle's sun shadow on the ground)"
)


def lines(result: Dict, top: int = 5) -> List[str]:
    """What a user reads of learnt rules."""
    what = result["target"] or "failure"
    out = [
        f"rules of {', '.join(result.get('campaigns') or ['the campaign'])} ({what} findings: {result['findings']} in {result['scenarios']} scenarios, {result['distinct']} "
        f"distinct; base rate {result['base_rate']:.3f} of distinct findings among the scenarios without a "
        f"repeated one; a rule is a leaf of a depth-{DEPTH} tree with at least {LIFT:g}x that rate and "
        f"{MIN_DISTINCT} distinct findings, learnt from this campaign: it holds only once checked on fresh "
        "samples, asg_analysis.rules check)"
    ]
    if not result["rules"]:
        out.append("  no rule: no leaf of the tree reaches twice the base rate")
    else:
        out.append(TERMS)
    for r in result["rules"][:top]:
        ex = r["example"]
        out.append(
            f"  {r.get('words', r['text'])}: {r['distinct']} distinct findings in {r['support']} ({r['precision']:.2f}, "
            f"{r['lift']:.1f}x), {100 * r['share_of_distinct']:.0f} % of the distinct findings and "
            f"{100 * r['share_of_findings']:.0f} % of all; e.g. {ex['campaign']} job {ex['job']}"
        )
    return out


def _pct(lo_hi) -> str:
    return f"[{100 * lo_hi[0]:.1f}, {100 * lo_hi[1]:.1f}]"


def markdown(learnt: Dict, checked: Optional[Dict] = None, top: int = 5) -> str:
    """A record's table of learnt rules (in the campaigns they came from) and, for the rule the
    protocol checked (the file's first), its precision on fresh samples against the base rate."""
    rows = [
        "| rule | in-sample: distinct findings / scenarios (precision, lift) | share of distinct findings | "
        "fresh samples: findings / scenarios (precision, 95 % CI) | base rate (95 % CI) | ratio | Fisher p | "
        "a finding it holds (campaign, job) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for i, r in enumerate(learnt["rules"][:top]):
        fresh = base = ratio = p = "not checked"
        if checked is not None and i == 0:
            c = checked
            fresh = f"{c['rule_findings']} / {c['rule_scenarios']} ({100 * c['precision']:.1f} %, {_pct(c['precision_ci'])})"
            base = f"{c['base_findings']} / {c['base_scenarios']} ({100 * c['base_rate']:.1f} %, {_pct(c['base_ci'])})"
            ratio, p = f"{c['ratio']:.2f}x", f"{c['fisher_p']:.3f}"
        rows.append(
            f"| `{r['text']}` | {r['distinct']} / {r['support']} ({100 * r['precision']:.0f} %, {r['lift']:.1f}x) | "
            f"{100 * r['share_of_distinct']:.0f} % | {fresh} | {base} | {ratio} | {p} | "
            f"{r['example']['campaign']} {r['example']['job']} |"
        )
    return "\n".join(rows) + "\n"


def run(argv=None) -> int:
    p = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    le = sub.add_parser("learn", help="rules from a campaign's results")
    le.add_argument("exports", nargs="*", help="compact exports (.jsonl.gz) of one experiment")
    le.add_argument("--store", default="", help="a campaign store instead of exports")
    le.add_argument(
        "--campaign", default="", help="the store's campaign (default: the one that stored a scenario last)"
    )
    le.add_argument("--target", default="auto", help="flaw, regression, failure, or auto (the campaign's reward)")
    le.add_argument("--out", default="", help="write the rules here (JSON)")
    ch = sub.add_parser("check", help="a rule on fresh samples against the base rate")
    ch.add_argument("rules", help="the rules file the rule-sampler campaigns ran")
    ch.add_argument("exports", nargs="+", help="the rule-sampler campaigns' exports")
    ch.add_argument("--base", nargs="+", required=True, help="the random campaigns' exports (same experiment)")
    ch.add_argument("--target", default="flaw")
    ch.add_argument("--out", default="")
    a = p.parse_args(argv)
    try:
        if a.cmd == "learn":
            from asg_analysis.exports import experiment_of, read_rows, target_of

            rows, camp = read_rows(a.exports, a.store, a.campaign)
            target = target_of(camp) if a.target == "auto" else (None if a.target == "failure" else a.target)
            result = learn(rows, experiment_of(camp), target)
            print("\n".join(lines(result)))
        else:
            from asg_analysis.exports import read_rows

            base, _ = read_rows(a.base, "", "")
            rule_rows, _ = read_rows(a.exports, "", "")
            result = dict(check(rule_rows, base, a.target), rules=a.rules)
            print(json.dumps(result, indent=1))
    except (ValueError, OSError) as e:
        print(f"rules: {e}", file=sys.stderr)
        return 2
    if a.out:
        with open(a.out, "w") as f:
            json.dump(result, f, indent=1, sort_keys=True)
    return 0
