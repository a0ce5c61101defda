"""The depth stack's cores (no ROS): the elevation grid and the arc lattice."""

import numpy as np
import pytest

from asg_depth_stack.arcs import ArcParams, ArcPlanner, rollout
from asg_depth_stack.grid import ElevationGrid, GridParams


def ground(x0, x1, y0, y1, z=0.0, step=0.1):
    xs, ys = np.meshgrid(np.arange(x0, x1, step), np.arange(y0, y1, step))
    return np.stack([xs.ravel(), ys.ravel(), np.full(xs.size, z)], axis=1)


def test_a_bush_is_an_obstacle_a_slope_is_not():
    g = ElevationGrid(GridParams(), (0.0, 0.0))
    slope = ground(2, 10, -3, 3)
    slope[:, 2] = 0.3 * slope[:, 0]  # a 30 % hill: 0.15 m across a cell
    bush = np.array([[6.1 + dx, 0.1 + dy, h] for dx in (0, 0.2) for dy in (0, 0.2) for h in (1.8, 2.0, 2.5)])
    g.insert(np.vstack([slope, bush]), (0.0, 0.0, 1.4))
    obs = g.centres(g.obstacles())
    assert len(obs) >= 1
    assert np.all(np.hypot(obs[:, 0] - 6.25, obs[:, 1] - 0.25) < 0.6)  # only the bush's cell(s)


def test_range_limits_and_points_outside_the_map_are_ignored():
    g = ElevationGrid(GridParams(size=20.0, max_range=5.0), (0.0, 0.0))
    far = np.array([[8.0, 0.0, 0.0], [8.0, 0.0, 2.0]])  # beyond max_range
    out = np.array([[50.0, 0.0, 0.0]])
    nan = np.array([[np.nan, 1.0, 1.0]])
    assert g.insert(np.vstack([far, out, nan]), (0.0, 0.0, 1.4)) == 0
    assert not g.obstacles().any()
    with pytest.raises(ValueError, match="cell"):
        GridParams(cell=0.0).check()


def test_rollout_of_an_arc_keeps_its_radius():
    pts = rollout(0.0, 0.0, 0.0, 0.2, 10.0, 0.5)
    centre = np.array([0.0, 5.0])  # left turn of radius 5 m
    assert np.allclose(np.hypot(*(pts - centre).T), 5.0)
    assert np.allclose(rollout(1.0, 2.0, np.pi / 2, 0.0, 2.0, 1.0), [[1.0, 3.0], [1.0, 4.0]])


def test_straight_to_the_goal_when_nothing_is_in_the_way():
    c = ArcPlanner(ArcParams()).choose(0.0, 0.0, 0.0, (50.0, 0.0), None)
    assert not c.blocked
    assert c.curvature == 0.0 and c.yaw_rate == 0.0
    assert c.speed == pytest.approx(5.0)


def test_an_obstacle_on_the_route_is_passed_with_clearance_and_slower():
    p = ArcParams()
    obstacle = np.array([[6.0, 0.0], [6.0, 0.5], [6.0, -0.5]])
    c = ArcPlanner(p).choose(0.0, 0.0, 0.0, (50.0, 0.0), obstacle)
    assert not c.blocked and c.curvature != 0.0
    pts = rollout(0.0, 0.0, 0.0, c.curvature, p.horizon, p.step)
    assert np.sqrt(((pts[:, None] - obstacle[None]) ** 2).sum(-1)).min() >= p.clearance
    assert c.speed < p.speed


def test_a_wall_stops_the_vehicle():
    wall = np.array([[3.0, y] for y in np.arange(-15, 15, 0.5)])
    c = ArcPlanner(ArcParams()).choose(0.0, 0.0, 0.0, (50.0, 0.0), wall)
    assert c.blocked and c.speed == 0.0
    with pytest.raises(ValueError, match="odd"):
        ArcParams(arcs=4).check()
