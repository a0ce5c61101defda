"""asg_analysis.stats: intervals, exact tests and rates over seeds."""

import math

import pytest

from asg_analysis import stats


def test_statistics_over_seeds():
    lo, hi = stats.bootstrap_ci([4, 5, 6, 5, 4, 6, 5, 5])
    assert 4.4 < lo < 5.0 < hi < 5.6
    assert stats.bootstrap_ci([3, 3, 3]) == (3.0, 3.0)
    # Every seed of a above every seed of b: the smallest exact two-sided p for 8 against 8.
    mw = stats.mann_whitney([10, 11, 12, 13, 14, 15, 16, 17], [1, 2, 3, 4, 5, 6, 7, 8])
    assert mw["effect"] == 1.0 and mw["p"] == pytest.approx(2 / 12870, rel=1e-6)
    assert stats.mann_whitney([1, 2, 3], [1, 2, 3])["p"] == pytest.approx(1.0)
    ratio, rlo, rhi = stats.ratio_ci([6, 6, 6, 6], [2, 2, 2, 2])
    assert (ratio, rlo, rhi) == (3.0, 3.0, 3.0)
    # No finding on either side (the first depth pair): undefined, never inf, and no target is met on it.
    assert all(math.isnan(x) for x in stats.ratio_ci([0, 0, 0], [0, 0, 0]))
    assert stats.ratio_ci([1, 0, 0], [0, 0, 0])[0] == math.inf
    rows = stats.compare({"td3": [6, 7, 8], "random": [1, 2, 3], "route": [5, 6, 7]}, "td3")
    assert [r["arm"] for r in rows] == ["td3", "random", "route"]
    assert rows[0]["p"] is None and rows[1]["ratio"] == pytest.approx(3.5) and rows[1]["effect"] == 1.0
    with pytest.raises(ValueError, match="default"):
        stats.compare({"a": [1]}, "b")
    # The design loop's endpoint counts flaw and model findings, nothing else, over the first jobs.
    rows = [{"job": j, "attribution": c} for j, c in enumerate(["flaw", "model", "stack", None, "flaw", "model"])]
    assert stats.per_thousand(rows, "findings", 4) == 500.0
    assert stats.per_thousand(rows, "findings", 6) == pytest.approx(4000 / 6)
    assert stats.per_thousand(rows, "flaw", 6) == pytest.approx(2000 / 6)
