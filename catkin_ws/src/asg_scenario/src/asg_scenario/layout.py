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


class RouteFrame:
    """Coordinates along the straight start-goal route of a scenario: `t` [-] the fraction of the
    way from start to goal, `d` [m] the signed distance to the left of it (looking from start to
    goal). The usable `t` range `t_range` leaves out the safety radius around start and goal, where
    the simulator removes obstacles. Used by route-random and the route-relative action space."""

    def __init__(self, scenario: dict):
        op = scenario["operational"]
        self.size = float(scenario["structural"]["landscape"]["size"])
        self.start = np.array([op["start_x"], op["start_y"]], dtype=np.float64)
        self.along = np.array([op["goal_x"], op["goal_y"]], dtype=np.float64) - self.start
        self.length = float(np.linalg.norm(self.along))
        margin = min(0.45, float(op.get("safety_radius", 0.0)) / max(self.length, 1e-9))
        self.t_range = (margin, 1.0 - margin)
        self.normal = np.array([-self.along[1], self.along[0]]) / max(self.length, 1e-9)

    @property
    def edge_m(self) -> float:
        """[m] the largest distance from the route's line to a corner of the landscape's square:
        a lateral offset this large reaches the square's edge from any point of the route."""
        corners = np.array([[0.0, 0.0], [0.0, self.size], [self.size, 0.0], [self.size, self.size]])
        return float(np.max(np.abs((corners - self.start) @ self.normal)))

    def point(self, t, d) -> np.ndarray:
        """x, y [m] of route coordinates (t [-], d [m]) (arrays broadcast), clipped to the
        landscape's nominal square."""
        t, d = np.asarray(t, dtype=np.float64)[..., None], np.asarray(d, dtype=np.float64)[..., None]
        return np.clip(self.start + t * self.along + d * self.normal, 0.0, self.size)
