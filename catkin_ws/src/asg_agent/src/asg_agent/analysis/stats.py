"""Statistics over seeds (issue #37; no ROS): a comparison of search methods reports per-seed
counts, a bootstrap 95 % interval of each arm's mean, a Mann-Whitney U test between arms and an
effect size, computed here and nowhere by hand.

- `bootstrap_ci`: percentile interval of a statistic over resamples of the seeds (seeded, so a
  table is reproducible);
- `mann_whitney`: SciPy's two-sided Mann-Whitney U test (exact for up to 20 seeds an arm without
  ties, else the normal approximation with the tie correction)
  and the rank-biserial correlation as its effect size (Cliff's delta: +1 when every seed of the
  first arm beats every seed of the second);
- `ratio_ci`: the ratio of two arms' means with a bootstrap interval (each arm resampled apart);
- `compare`: all of it for a default arm against each other arm, as rows for a table.
"""

from typing import Callable, Dict, Optional, Sequence, Tuple

import numpy as np

LEVEL = 0.95  # [-] interval coverage
RESAMPLES = 10_000  # bootstrap resamples


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


def mann_whitney(a: Sequence[float], b: Sequence[float]) -> Dict[str, float]:
    """Two-sided Mann-Whitney U of a against b: {u, p, effect} (effect: rank-biserial, in [-1, 1])."""
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


def ratio_ci(
    a: Sequence[float], b: Sequence[float], level: float = LEVEL, n: int = RESAMPLES, seed: int = 0
) -> Tuple[float, float, float]:
    """(mean(a) / mean(b), lo, hi); inf where b's resampled mean is 0."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    rng = np.random.default_rng(seed)
    ma = a[rng.integers(0, a.size, size=(n, a.size))].mean(axis=1)
    mb = b[rng.integers(0, b.size, size=(n, b.size))].mean(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(mb > 0, ma / np.where(mb > 0, mb, 1.0), np.inf)
    lo, hi = np.quantile(r, [(1 - level) / 2, 1 - (1 - level) / 2])
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
