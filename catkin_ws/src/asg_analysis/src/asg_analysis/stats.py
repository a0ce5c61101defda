"""Statistics over seeds (issue #37; no ROS): a comparison of search methods reports per-seed
counts, a bootstrap 95 % interval of each arm's mean, a Mann-Whitney U test between arms and an
effect size, computed here and nowhere by hand.

- `bootstrap_ci`: percentile interval of a statistic over resamples of the seeds (seeded, so a
  table is reproducible);
- `mann_whitney`: the two-sided Mann-Whitney U test, exact with ties (issue #67): a permutation
  test of U (mid-ranks for ties) over every split of the pooled seeds into arms of the same sizes
  (252 splits at 5 against 5), the p-value the share of splits whose
  |U - n1 n2 / 2| is at least the observed one; and the rank-biserial correlation as its effect
  size (Cliff's delta: +1 when every seed of the first arm beats every seed of the second).
  `mann_whitney_scipy` keeps SciPy's `mannwhitneyu` (exact only without ties, else the normal
  approximation), what round 5's table used;
- `ratio_ci`: the ratio of two arms' means with a bootstrap interval (each arm resampled apart);
- `compare`: all of it for a default arm against each other arm, as rows for a table.
"""

import math
from typing import Callable, Dict, Optional, Sequence, Tuple

import numpy as np

PROG = "python3 -m asg_analysis stats"

LEVEL = 0.95  # [-] interval coverage
RESAMPLES = 10_000  # bootstrap resamples


def exact_interval(k: int, n: int, level: float = LEVEL) -> list:
    """Clopper-Pearson interval of a binomial rate k / n."""
    from scipy.stats import binomtest

    ci = binomtest(k, n).proportion_ci(confidence_level=level, method="exact")
    return [float(ci.low), float(ci.high)]


def bootstrap_ci(
    values: Sequence[float], stat: Callable = np.mean, level: float = LEVEL, n: int = RESAMPLES, seed: int = 0
) -> Tuple[float, float]:
    v = np.asarray(values, float)
    if v.size == 0:
        raise ValueError("bootstrap_ci needs at least one value")
    rng = np.random.default_rng(seed)
    draws = stat(v[rng.integers(0, v.size, size=(n, v.size))], axis=1)
    lo, hi = np.quantile(draws, [(1 - level) / 2, 1 - (1 - level) / 2])
    return float(lo), float(hi)


#: the most splits the exact test enumerates (10 against 10 has 184,756)
EXACT_LIMIT = 200_000


def u_statistic(a: Sequence[float], b: Sequence[float]) -> float:
    """Mann-Whitney U of a against b with mid-ranks: pairs a > b, plus half the ties."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float((a[:, None] > b[None, :]).sum() + 0.5 * (a[:, None] == b[None, :]).sum())


def mann_whitney(a: Sequence[float], b: Sequence[float]) -> Dict[str, float]:
    """Two-sided Mann-Whitney U of a against b, exact with ties (a permutation test over every
    split; see the module's text): {u, p, effect, method} (effect: rank-biserial, in [-1, 1])."""
    from itertools import combinations

    a, b = np.asarray(a, float), np.asarray(b, float)
    if a.size == 0 or b.size == 0:
        raise ValueError("mann_whitney needs values in both arms")
    splits = math.comb(a.size + b.size, a.size)
    if splits > EXACT_LIMIT:
        raise ValueError(
            f"mann_whitney: {a.size} against {b.size} seeds is past the exact test's {EXACT_LIMIT:,} splits"
        )
    pooled = np.concatenate([a, b])
    # every split of the pooled values into an arm of a's size and the rest (SciPy's
    # permutation_test does the same but needs two values an arm)
    first = np.zeros((splits, pooled.size), bool)
    for k, idx in enumerate(combinations(range(pooled.size), a.size)):
        first[k, list(idx)] = True
    gt = (pooled[:, None] > pooled[None, :]).astype(float) + 0.5 * (pooled[:, None] == pooled[None, :])
    u_all = np.einsum("ki,ij,kj->k", first.astype(float), gt, (~first).astype(float))
    half = a.size * b.size / 2.0
    u = u_statistic(a, b)
    p = float(np.mean(np.abs(u_all - half) >= abs(u - half) - 1e-9))
    return {"u": u, "p": p, "effect": 2.0 * u / (a.size * b.size) - 1.0, "method": "exact"}


def mann_whitney_scipy(a: Sequence[float], b: Sequence[float]) -> Dict[str, float]:
    """Round 5's test: SciPy's two-sided `mannwhitneyu`, exact without ties, else the normal
    approximation with the tie correction: {u, p, effect, method}."""
    from scipy.stats import mannwhitneyu

    a, b = np.asarray(a, float), np.asarray(b, float)
    if a.size == 0 or b.size == 0:
        raise ValueError("mann_whitney needs values in both arms")
    # Exact where it can be (no ties, small samples: 8 seeds against 8 has 12,870 orderings),
    # else the normal approximation with the tie correction.
    ties = np.unique(np.concatenate([a, b])).size < a.size + b.size
    method = "asymptotic" if ties or max(a.size, b.size) > 20 else "exact"
    res = mannwhitneyu(a, b, alternative="two-sided", method=method)
    u = float(res.statistic)
    return {"u": u, "p": float(res.pvalue), "effect": 2.0 * u / (a.size * b.size) - 1.0}


def seeds_per_arm(a: Sequence[float], b: Sequence[float], alpha: float = 0.05, power: float = 0.8) -> Dict:
    """How many seeds an arm a comparison of a and b would need to tell them apart: the two-sample
    normal approximation n = 2 s^2 (z_(1-alpha/2) + z_power)^2 / d^2, with d the difference of the
    arms' means and s^2 the mean of their sample variances (the per-seed spread seen so far). An
    estimate for planning a protocol, not a test; None where the means are equal."""
    from scipy.stats import norm

    a, b = np.asarray(a, float), np.asarray(b, float)
    diff = float(b.mean() - a.mean())
    var = float((a.var(ddof=1) + b.var(ddof=1)) / 2.0)
    z = float(norm.ppf(1 - alpha / 2) + norm.ppf(power))
    n = None if diff == 0 else int(math.ceil(2.0 * var * z * z / (diff * diff)))
    return {"difference": diff, "pooled_sd": math.sqrt(var), "alpha": alpha, "power": power, "seeds_per_arm": n}


def ratio_ci(
    a: Sequence[float], b: Sequence[float], level: float = LEVEL, n: int = RESAMPLES, seed: int = 0
) -> Tuple[float, float, float]:
    """(mean(a) / mean(b), lo, hi); inf where b's resampled mean is 0; all three nan where neither
    side found any (the ratio is undefined, and no target on it is met)."""
    if not np.any(a) and not np.any(b):
        return float("nan"), float("nan"), float("nan")
    a, b = np.asarray(a, float), np.asarray(b, float)
    rng = np.random.default_rng(seed)
    ma = a[rng.integers(0, a.size, size=(n, a.size))].mean(axis=1)
    mb = b[rng.integers(0, b.size, size=(n, b.size))].mean(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(mb > 0, ma / np.where(mb > 0, mb, 1.0), np.inf)
    # "nearest": an interval end is a resampled ratio itself (inf where the arm's mean was 0)
    lo, hi = np.quantile(r, [(1 - level) / 2, 1 - (1 - level) / 2], method="nearest")
    point = a.mean() / b.mean() if b.mean() > 0 else float("inf")
    return float(point), float(lo), float(hi)


def compare(arms: Dict[str, Sequence[float]], default: str, seed: int = 0) -> list:
    """Rows {arm, seeds, counts, mean, lo, hi, ratio, ratio_lo, ratio_hi, p, effect} of every arm
    (per-seed values, e.g. flaw findings per 1,000), the default first; the test and the ratio are
    the default's against that arm (None for the default's own row)."""
    if default not in arms:
        raise ValueError(f"default arm {default!r} not among {sorted(arms)}")
    rows = []
    for name in [default] + sorted(k for k in arms if k != default):
        v = list(arms[name])
        lo, hi = bootstrap_ci(v, seed=seed)
        row: Dict[str, Optional[float]] = {
            "arm": name,
            "seeds": len(v),
            "counts": v,
            "mean": float(np.mean(v)),
            "lo": lo,
            "hi": hi,
            "ratio": None,
            "ratio_lo": None,
            "ratio_hi": None,
            "p": None,
            "effect": None,
        }
        if name != default:
            mw = mann_whitney(arms[default], v)
            ratio, rlo, rhi = ratio_ci(arms[default], v, seed=seed)
            row.update(ratio=ratio, ratio_lo=rlo, ratio_hi=rhi, p=mw["p"], effect=mw["effect"])
        rows.append(row)
    return rows


# -- the command: arms of exports compared on one score -----------------------------------------

SCORES = {
    # key: (label, per-row predicate on an export row)
    "flaw": ("flaw findings (three-stack attribution)", lambda r: r.get("attribution") == "flaw"),
    "model": ("model findings", lambda r: r.get("attribution") == "model"),
    # the design loop's endpoint (issue #40, experiments/protocol-design-loop.yaml)
    "findings": ("flaw + model findings", lambda r: r.get("attribution") in ("flaw", "model")),
    "perception": ("perception findings (round 3: proxy >= 3, ground truth < 2)", None),
    "differential": ("differential findings (proxy - ground truth >= 1)", None),
    "collisions": ("perception collisions (ground truth reached the goal)", None),
    "ge3": ("proxy >= 3", None),
}


def _predicate(score: str):
    from asg_agent.scoring import attribution as attr

    return {
        "perception": attr.perception_finding,
        "differential": attr.differential_finding,
        "collisions": attr.perception_collision,
        "ge3": lambda r: r["proxy"] is not None and r["proxy"] >= attr.FINDING,
    }.get(score) or SCORES[score][1]


def per_thousand(rows, score: str, budget: int) -> float:
    """A score's count per 1,000 scenarios over the first `budget` jobs of an export."""
    keep = [r for r in rows if r["job"] < budget]
    pred = _predicate(score)
    return 1000.0 * sum(bool(pred(r)) for r in keep) / max(1, len(keep))


def markdown(rows: list, label: str) -> str:
    out = [
        f"| arm | seeds | {label} per 1,000, per seed | mean (95 % interval) | default / arm (95 % interval) | "
        "Mann-Whitney p | effect |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        ratio = (
            "-"
            if r["ratio"] is None
            else ("inf" if r["ratio"] == float("inf") else f"{r['ratio']:.2f}")
            + (f" ({r['ratio_lo']:.2f}-{r['ratio_hi']:.2f})" if r["ratio"] is not None else "")
        )
        out.append(
            f"| {r['arm']} | {r['seeds']} | {', '.join(f'{v:g}' for v in r['counts'])} | "
            f"{r['mean']:.1f} ({r['lo']:.1f}-{r['hi']:.1f}) | {ratio} | "
            f"{'-' if r['p'] is None else format(r['p'], '.3f')} | {'-' if r['effect'] is None else format(r['effect'], '+.2f')} |"
        )
    return "\n".join(out)


def run(argv=None) -> int:
    import argparse
    import sys

    from asg_agent.records.export import read_export

    p = argparse.ArgumentParser(prog=PROG, description="arms of campaign exports compared on one score, over seeds")
    p.add_argument("arms", nargs="+", help="ARM=EXPORT[,EXPORT...] (one export per seed)")
    p.add_argument("--default", required=True, help="the arm the others are compared with")
    p.add_argument("--score", default="flaw", choices=sorted(SCORES))
    p.add_argument("--budget", type=int, default=1000, help="scenarios per campaign counted (first jobs)")
    a = p.parse_args(argv)
    arms = {}
    try:
        for spec in a.arms:
            name, _, files = spec.partition("=")
            if not files:
                raise ValueError(f"{spec!r}: expected ARM=EXPORT[,EXPORT...]")
            arms[name] = [per_thousand(read_export(f)[1], a.score, a.budget) for f in files.split(",")]
        rows = compare(arms, a.default)
    except (OSError, ValueError, KeyError) as e:
        print(f"stats: {e}", file=sys.stderr)
        return 2
    print(markdown(rows, SCORES[a.score][0]))
    return 0
