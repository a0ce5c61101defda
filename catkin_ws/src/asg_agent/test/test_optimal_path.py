"""The optimal path against cases with known answers."""

import math

import numpy as np
import pytest

from asg_agent.scoring.optimal_path import Disc, shortest_path


def detour_length(d, r):
    """Start and goal point at distance d each side of a disc of radius r centred on the line:
    two tangents and the arc between them."""
    t = math.sqrt(d * d - r * r)
    arc = r * (math.pi - 2 * math.acos(r / d))
    return 2 * t + arc


def test_free_line():
    p = shortest_path((0, 0), (30, 40), 5.0, [])
    assert abs(p.length - 45.0) < 1e-9


def test_start_inside_goal_circle():
    assert shortest_path((1, 1), (2, 2), 5.0, [Disc(1.5, 1.5, 0.2)]).length == 0.0


def test_one_disc_across_the_line_is_the_analytic_detour():
    for d, r in ((10.0, 3.0), (20.0, 7.5), (15.0, 1.0)):
        # Goal circle of radius ~0: the goal is the point (2d, 0).
        p = shortest_path((0.0, 0.0), (2 * d, 0.0), 1e-9, [Disc(d, 0.0, r)])
        assert abs(p.length - detour_length(d, r)) < 1e-6 * d, (d, r, p.length)


def test_goal_circle_shortens_the_last_leg():
    d, r, R = 20.0, 3.0, 5.0
    p = shortest_path((0.0, 0.0), (2 * d, 0.0), R, [Disc(d, 0.0, r)])
    # The last leg heads to the goal centre and stops R short of it: the detour minus R.
    assert abs(p.length - (detour_length(d, r) - R)) < 1e-6
    end = p.points[-1]
    assert abs(math.dist(end, (2 * d, 0.0)) - R) < 1e-6


def test_wall_of_overlapping_discs_is_gone_round():
    # Discs of radius 1.5 every 2 m from y = -10 to 10 at x = 20: a wall 23 m long.
    wall = [Disc(20.0, y, 1.5) for y in range(-10, 11, 2)]
    p = shortest_path((0.0, 0.0), (40.0, 0.0), 1e-9, wall)
    # Round an end of the wall: at least the two straight lines to the wall's end cap.
    lower = 2 * math.hypot(20.0, 11.5)
    assert lower - 1e-6 <= p.length <= lower * 1.01
    # And the path never enters a disc.
    pts = np.asarray(p.points)
    for d in wall:
        assert np.min(np.hypot(pts[:, 0] - d.x, pts[:, 1] - d.y)) > d.r - 1e-3


def test_unreachable_goal():
    # A ring of discs around the goal.
    ring = [Disc(20 + 6 * math.cos(a), 6 * math.sin(a), 1.6) for a in np.linspace(0, 2 * math.pi, 13)[:-1]]
    p = shortest_path((0.0, 0.0), (20.0, 0.0), 1.0, ring)
    assert math.isinf(p.length) and p.points == []


def test_against_a_fine_grid_search():
    rng = np.random.default_rng(4)
    for _ in range(5):
        discs = [Disc(*rng.uniform(15, 85, 2), rng.uniform(1.5, 4.0)) for _ in range(8)]
        exact = shortest_path((20.0, 20.0), (80.0, 80.0), 11.0, discs).length
        grid = _grid_length(discs)
        # A 16-connected grid of 0.25 m overestimates by a few per mille at most.
        assert exact <= grid + 1e-6
        assert grid <= exact * 1.02, (exact, grid)


def test_discs_reaching_into_the_goal_circle_against_a_fine_grid_search():
    # The worker removes obstacles by centre distance (safety radius 11 m = goal radius), so a
    # disc centred 11-13 m from the goal reaches into the goal circle and can hide the head-on
    # legs near it; the path then ends where the rim crosses the circle.
    rng = np.random.default_rng(7)
    for _ in range(6):
        discs = []
        for _ in range(3):
            ang = math.radians(225 + rng.uniform(-35, 35))
            rad = rng.uniform(11.0, 13.0)
            discs.append(Disc(80 + rad * math.cos(ang), 80 + rad * math.sin(ang), rng.uniform(1.5, 2.7)))
        exact = shortest_path((20.0, 20.0), (80.0, 80.0), 11.0, discs).length
        grid = _grid_length(discs)
        assert exact <= grid + 1e-6, (exact, grid)
        assert grid <= exact * 1.01, (exact, grid)


def test_a_disc_on_the_head_on_leg_inside_the_goal_circle():
    # One disc across the line at the circle: the head-on leg is blocked, the path ends beside it,
    # no further than where the disc's rim crosses the circle (found by direct search here).
    d = Disc(21.0, 0.0, 2.0)
    p = shortest_path((0.0, 0.0), (30.0, 0.0), 10.0, [d])
    best = math.inf
    for phi in np.linspace(-math.pi, math.pi, 200001):
        q = (30 - 10 * math.cos(phi), 10 * math.sin(phi))
        if math.dist(q, (d.x, d.y)) >= d.r - 1e-9 and not _blocked((0.0, 0.0), q, d):
            best = min(best, math.dist((0.0, 0.0), q))
    assert p.length <= best + 1e-6
    assert p.length >= 20.0  # no shorter than the free head-on leg
    assert p.length == pytest.approx(best, abs=0.02)  # the straight end is the best here


def _blocked(p, q, d):
    dx, dy = q[0] - p[0], q[1] - p[1]
    t = max(0.0, min(1.0, ((d.x - p[0]) * dx + (d.y - p[1]) * dy) / (dx * dx + dy * dy)))
    return math.hypot(p[0] + t * dx - d.x, p[1] + t * dy - d.y) < d.r - 1e-7


def _grid_length(discs, h=0.25):
    import heapq

    n = int(100 / h) + 1
    xs = np.arange(n) * h
    X, Y = np.meshgrid(xs, xs, indexing="ij")
    free = np.ones((n, n), bool)
    for d in discs:
        free &= np.hypot(X - d.x, Y - d.y) >= d.r
    goal = np.hypot(X - 80, Y - 80) <= 11.0
    moves = [
        (dx, dy) for dx in range(-2, 3) for dy in range(-2, 3) if (dx, dy) != (0, 0) and math.gcd(abs(dx), abs(dy)) == 1
    ]
    start = (int(20 / h), int(20 / h))
    dist = np.full((n, n), np.inf)
    dist[start] = 0
    heap = [(0.0, start)]
    while heap:
        du, (i, j) = heapq.heappop(heap)
        if du > dist[i, j]:
            continue
        if goal[i, j]:
            return du
        for dx, dy in moves:
            a, b = i + dx, j + dy
            if 0 <= a < n and 0 <= b < n and free[a, b] and free[(i + a) // 2, (j + b) // 2]:
                w = h * math.hypot(dx, dy)
                if du + w < dist[a, b]:
                    dist[a, b] = du + w
                    heapq.heappush(heap, (du + w, (a, b)))
    return math.inf
