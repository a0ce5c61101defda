"""Judging where votes fell: phantom votes and votes in cast shadows."""

import os

from asg_scenario import load_scenario
from asg_scenario.votes import in_cast_shadow, phantom_votes, shadow_mask, shadow_votes

SHADOWS = os.path.join(os.path.dirname(__file__), "..", "..", "..", "..", "scenarios", "shadows.yaml")


def test_cast_shadow_geometry():
    s = load_scenario(SHADOWS)  # sun 18 deg above the horizon from yaw 10 deg
    # Juniper at (48, 47), 4.5 m: a shadow about 13.8 m long towards yaw 190 deg.
    assert in_cast_shadow(s, 48.0 - 5.0, 47.0 - 0.9)
    assert in_cast_shadow(s, 48.0 - 10.0, 47.0 - 1.7)
    assert not in_cast_shadow(s, 48.0 - 16.0, 47.0 - 2.8)  # past the tip
    assert not in_cast_shadow(s, 48.0 + 5.0, 47.0 + 0.9)  # on the sunny side
    assert not in_cast_shadow(s, 48.0 - 5.0, 47.0 + 3.0)  # beside it
    s["structural"]["layouts"][0]["instances"][0]["cast_shadow"] = False
    assert not in_cast_shadow(s, 48.0 - 5.0, 47.0 - 0.9)
    # A high sun shortens the shadow: 4.5 m / tan(60 deg) = 2.6 m.
    s = load_scenario(SHADOWS)
    s["textural"]["sun_inclination_deg"] = 60.0
    assert not in_cast_shadow(s, 48.0 - 5.0, 47.0 - 0.9)


def test_phantom_and_shadow_votes():
    s = load_scenario(SHADOWS)
    votes = [
        {"x": 48.0, "y": 47.0},  # on the juniper: explained
        {"x": 48.0 - 8.0, "y": 47.0 - 1.4},  # in its shadow, 8 m from it
        {"x": 20.0, "y": 20.0},
    ]  # open ground in the sun
    # The second vertex is 6.1 m from the bush at (44, 41) (radius 0.96): with 1 m cells it is
    # unexplained and in the shadow.
    assert phantom_votes(s, votes, 1.0) == 2
    assert shadow_votes(s, votes, 1.0) == 1
    # Not placed (removed by the worker), the juniper explains nothing and casts no shadow.
    assert phantom_votes(s, votes, 1.0, {(0, 0)}) == 3
    assert shadow_votes(s, votes, 1.0, {(0, 0)}) == 0


def test_shadow_mask_is_in_cast_shadow_point_by_point():
    """The array form gives in_cast_shadow's answer at every point of a 0.1 m grid around the
    juniper (edges included), under three suns and with the obstacle removed."""
    import numpy as np

    xs, ys = np.meshgrid(np.arange(25.0, 60.0, 0.1), np.arange(35.0, 55.0, 0.1))
    for inc, yaw, removed in ((18.0, 10.0, frozenset()), (3.0, 200.0, frozenset()), (45.0, 95.0, {(0, 0)})):
        s = load_scenario(SHADOWS)
        s["textural"].update(sun_inclination_deg=inc, sun_yaw_deg=yaw)
        mask = shadow_mask(s, xs, ys, removed)
        want = np.array([[in_cast_shadow(s, x, y, 0.0, removed) for x, y in zip(rx, ry)] for rx, ry in zip(xs, ys)])
        assert mask.shape == xs.shape and np.array_equal(mask, want)
        assert removed or 100 < want.sum() < want.size  # the shadow is on the grid, and not all of it
