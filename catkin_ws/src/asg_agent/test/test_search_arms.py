"""Issue #37's arms and statistics: route-biased random layouts, and the statistics over seeds."""

import os

import numpy as np
import pytest

from asg_agent.analysis import stats
from asg_agent.campaign.experiment import load_experiment
from asg_agent.search.methods import make_method

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))
EXP = os.path.join(REPO, "experiments", "exp1.yaml")


def _xy(exp, action):
    return (np.asarray(action[: exp.position_dim], float).reshape(-1, 2) + 1.0) * 0.5 * exp.size


def test_route_random_puts_every_obstacle_in_its_band_and_repeats():
    exp = load_experiment(EXP)
    op = exp.scenario["operational"]
    a, b = np.array([op["start_x"], op["start_y"]]), np.array([op["goal_x"], op["goal_y"]])
    m = make_method("route-random", exp, 4, options={"band": 3.0})
    for job in range(50):
        xy = _xy(exp, m.propose(job, 0, 0, None))
        t = ((xy - a) @ (b - a)) / ((b - a) @ (b - a))
        d = np.abs(np.cross(b - a, xy - a)) / np.linalg.norm(b - a)
        assert (d <= 3.0 + 1e-3).all()
        # beyond the safety radius around start and goal (obstacles there are removed)
        assert (np.linalg.norm(xy - a, axis=1) >= op["safety_radius"] - 3.01).all()
        assert (np.linalg.norm(xy - b, axis=1) >= op["safety_radius"] - 3.01).all()
        assert ((t > 0) & (t < 1)).all()
    again = make_method("route-random", exp, 4, options={"band": 3.0})
    assert np.array_equal(m.propose(17, 3, 2, None), again.propose(17, 0, 0, None))  # (seed, job) alone
    assert not np.array_equal(m.propose(17, 0, 0, None), m.propose(18, 0, 0, None))
    # share 0: uniform layouts, most obstacles far from the route
    far = make_method("route-random", exp, 4, options={"band": 3.0, "share": 0.0})
    xy = np.concatenate([_xy(exp, far.propose(j, 0, 0, None)) for j in range(50)])
    d = np.abs(np.cross(b - a, xy - a)) / np.linalg.norm(b - a)
    assert (d > 3.0).mean() > 0.8
    with pytest.raises(ValueError, match="band"):
        make_method("route-random", exp, 0, options={"band": 0.0})


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
    rows = stats.compare({"td3": [6, 7, 8], "random": [1, 2, 3], "route": [5, 6, 7]}, "td3")
    assert [r["arm"] for r in rows] == ["td3", "random", "route"]
    assert rows[0]["p"] is None and rows[1]["ratio"] == pytest.approx(3.5) and rows[1]["effect"] == 1.0
    with pytest.raises(ValueError, match="default"):
        stats.compare({"a": [1]}, "b")
