"""Proxy terms on hand-made trajectories."""

import math

import numpy as np
import pytest

from asg_agent.scoring import proxy


def scene(layouts=()):
    return {
        "structural": {"landscape": {"size": 100.0}, "layouts": list(layouts)},
        "operational": {
            "start_x": 20.0,
            "start_y": 20.0,
            "goal_x": 80.0,
            "goal_y": 80.0,
            "goal_radius": 11.0,
            "safety_radius": 11.0,
        },
    }


def straight(n=600):
    d = math.dist((20, 20), (80, 80)) - 11.0
    s = np.linspace(0, d, n)
    xy = np.stack([20 + s / math.sqrt(2), 20 + s / math.sqrt(2)], 1)
    return np.arange(n) / 60.0, xy


def test_straight_line_yaw_term_zero_and_plr_one():
    t, xy = straight()
    r = proxy.compute(scene(), t, xy, np.zeros(len(t)), [], "SUCCESS")
    assert r.yaw_term == 0.0
    assert abs(r.plr - 1.0) < 1e-9
    assert r.vis == -1.0  # nothing placed
    assert abs(r.proxy - (0.1 * -1 + 0 + 1)) < 1e-9


def test_known_detour():
    t, xy = straight()
    # Drive 10 m sideways and back at the start: 20 m more than the optimal 73.85 m.
    side = np.array([[20.0, 20.0], [20.0 + 10 / math.sqrt(2), 20.0 - 10 / math.sqrt(2)], [20.0, 20.0]])
    r = proxy.compute(scene(), t, np.vstack([side, xy]), np.zeros(len(t)), [], "SUCCESS")
    opt = math.dist((20, 20), (80, 80)) - 11.0
    assert abs(r.plr - (opt + 20.0) / opt) < 1e-9


def test_yaw_term_of_a_constant_turn():
    t = np.linspace(0, 10, 601)
    _, xy = straight(601)
    r = proxy.compute(scene(), t, xy, np.full(601, 0.5), [], "SUCCESS")
    assert abs(r.yaw_term - 10 * 0.25) < 1e-12  # (10 / N) * N * 0.5^2


def test_visibility_term():
    bush = {"visible": True, "cast_shadow": True, "x": 50.0, "y": 50.0, "yaw": 0.0, "scale": 1.0}
    s = scene(
        [
            {"mesh_name": "juniper", "instances": [dict(bush), dict(bush, x=40.0)]},
            {"mesh_name": "barberry", "instances": [dict(bush, x=21.0, y=21.0)]},
        ]
    )
    assert proxy.visibility_term(s, [1.0, 0.5, -1.0]) == 2 * 0.75 - 1
    assert proxy.visibility_term(s, [0.0, 0.0, -1.0]) == -1.0


def test_terminations():
    t, xy = straight()
    half = xy[: len(xy) // 2]
    r = proxy.compute(scene(), t[: len(half)], half, np.zeros(len(half)), [], "COLLISION")
    assert abs(r.plr - 1.0) < 1e-6  # driven half + the straight rest: no reward for stopping
    assert proxy.compute(scene(), t, xy, np.zeros(len(t)), [], "ERROR") is None
    with pytest.raises(ValueError):
        proxy.compute(scene(), t, xy, np.zeros(len(t)), [], "CRASHED")


def test_optimal_path_uses_placed_obstacles_only():
    tree = {"visible": True, "cast_shadow": True, "x": 50.0, "y": 50.0, "yaw": 0.0, "scale": 1.0}
    s = scene([{"mesh_name": "juniper", "instances": [tree]}])
    opt = proxy.optimal_length(s)
    assert opt > math.dist((20, 20), (80, 80)) - 11.0 + 0.05
    assert abs(proxy.optimal_length(s, [False]) - (math.dist((20, 20), (80, 80)) - 11.0)) < 1e-9
