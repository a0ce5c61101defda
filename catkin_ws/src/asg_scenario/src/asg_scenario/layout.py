"""Obstacle layouts as flat position vectors (no ROS imports).

The generator's action is the x, y of every obstacle instance of a scenario, in the flattened
order of its layouts (layout 0's instances, then layout 1's, ...): the same order as
RunScenarioResult.obstacle_visibility. These helpers move between that vector and a scenario.
"""

import copy
from typing import List, Sequence, Tuple

import numpy as np


def instance_count(scenario: dict) -> int:
    return sum(len(l["instances"]) for l in scenario["structural"]["layouts"])


def positions(scenario: dict) -> np.ndarray:
    """(n, 2) array of the instances' x, y [m], flattened layout order."""
    xy = [(i["x"], i["y"]) for l in scenario["structural"]["layouts"] for i in l["instances"]]
    return np.asarray(xy, dtype=np.float64).reshape(-1, 2)


def mesh_of_instances(scenario: dict) -> List[str]:
    return [l["mesh_name"] for l in scenario["structural"]["layouts"] for _ in l["instances"]]


def with_positions(scenario: dict, xy: Sequence[Tuple[float, float]]) -> dict:
    """A deep copy of `scenario` with the instances moved to `xy` [m] (n x 2, flattened order)."""
    xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    n = instance_count(scenario)
    if xy.shape[0] != n:
        raise ValueError(f"{xy.shape[0]} positions for {n} obstacle instances")
    out = copy.deepcopy(scenario)
    k = 0
    for layout in out["structural"]["layouts"]:
        for inst in layout["instances"]:
            inst["x"], inst["y"] = float(xy[k, 0]), float(xy[k, 1])
            k += 1
    return out


def random_positions(scenario: dict, rng: np.random.Generator) -> np.ndarray:
    """Uniform positions over the nominal square, (n, 2) [m], rounded to 1 cm."""
    size = scenario["structural"]["landscape"]["size"]
    return np.round(rng.uniform(0.0, size, size=(instance_count(scenario), 2)), 2)


def random_scene(scenario: dict, seed: int, scenario_id: int = None) -> dict:
    """`scenario` with its obstacles at seeded uniform random places (a reproducible test scene)."""
    s = with_positions(scenario, random_positions(scenario, np.random.default_rng(seed)))
    if scenario_id is not None:
        s["scenario_id"] = scenario_id
    return s
