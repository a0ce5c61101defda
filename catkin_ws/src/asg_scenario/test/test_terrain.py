"""asg_scenario.terrain mirrors asg_sim's Terrain (issue #27): the same heights at the points of
the shared table that asg_sim's gtest Terrain.HeightsAsInTheSharedTable checks as well."""

import os

import numpy as np

from asg_scenario import load_scenario
from asg_scenario.terrain import Terrain, scenario_terrain

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))


def test_heights_as_in_the_shared_table():
    t = scenario_terrain(load_scenario(os.path.join(REPO, "scenarios", "corpus", "good", "terrain.yaml")))
    table = np.loadtxt(os.path.join(REPO, "scenarios", "corpus", "terrain_heights.txt"))
    assert table.shape[0] > 250 and not t.flat
    got = t.heights(table[:, :2])
    assert np.max(np.abs(got - table[:, 2])) < 1e-9
    assert abs(t.height(float(table[7, 0]), float(table[7, 1])) - table[7, 2]) < 1e-9  # scalars too
    assert np.ptp(table[:, 2]) > 2.0  # the table is not a flat ground


def test_flat_when_absent_or_zero():
    s = load_scenario(os.path.join(REPO, "scenarios", "exp1.yaml"))
    for t in (scenario_terrain(s), scenario_terrain({"structural": {}}), Terrain({"hills": [], "amplitude_m": 0.0})):
        assert t.flat and t.height(12.0, 40.0) == 0.0
