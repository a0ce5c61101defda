"""Where a finding happened, and which findings are distinct (issue #78; no ROS).

A finding's *place* is the obstacle the stack under test hit (its class, the scenario's mesh name,
and its position [m]) or, when the run touched nothing (a timeout, a stuck vehicle, a run that
reached the goal with a high score), the class NO_CONTACT at the position where the vehicle ended.

A finding is *distinct* when its place lies at least `radius` [m] from the place of every earlier
distinct finding of the same campaign, or is of another class (protocol version 4's endpoint:
PRIMARY_RADIUS_M, REPORTED_RADII_M beside it). "Earlier" is job order, so the count is a function
of the campaign's rows alone: the campaign's progress bar, store summary, TensorBoard scalars,
the search methods that avoid places already found, and the study analysis all count with
`DistinctPlaces`, the one definition.
"""

from typing import Dict, Iterable, List, Optional, Sequence, Tuple

import numpy as np

PRIMARY_RADIUS_M = 2.0  # [m] protocol v4's primary radius
REPORTED_RADII_M = (1.0, 2.0, 5.0)  # [m] reported beside it
NO_CONTACT = "no contact"  # the class of a finding that hit no obstacle

Place = Tuple[str, float, float]  # (class, x [m], y [m])


def place(meshes: Sequence[str], positions, collision_with: Optional[int], end_xy) -> Place:
    """The place of a run: the obstacle `collision_with` (an index into `meshes` and `positions`
    [m]) when it hit one, else (NO_CONTACT, where it ended [m])."""
    if collision_with is not None:
        if not 0 <= int(collision_with) < len(meshes):
            raise ValueError(f"collision_with {collision_with} names no obstacle of {len(meshes)}")
        x, y = positions[int(collision_with)]
        return (str(meshes[int(collision_with)]), float(x), float(y))
    x, y = np.asarray(end_xy, float).reshape(-1, 2)[-1]
    return (NO_CONTACT, float(x), float(y))


def place_of_row(row: dict) -> Place:
    """The place of an export row (records/export.py: meshes, positions, collision_with,
    trajectory_xy)."""
    hit = row.get("collision_with") if row.get("termination") == "COLLISION" else None
    return place(row["meshes"], row["positions"], hit, row["trajectory_xy"])


class DistinctPlaces:
    """The distinct places of a campaign so far, at `radius` [m]."""

    def __init__(self, radius: float = PRIMARY_RADIUS_M):
        if not radius > 0.0:
            raise ValueError(f"radius {radius} [m] must be > 0")
        self.radius = float(radius)
        self.by_class: Dict[str, List[Tuple[float, float]]] = {}

    def __len__(self) -> int:
        return sum(len(v) for v in self.by_class.values())

    def near(self, cls: str, xy, radius: Optional[float] = None) -> np.ndarray:
        """Whether each point of `xy` (m x 2 [m]) lies within `radius` (default: this set's) of a
        distinct place of class `cls`."""
        r = self.radius if radius is None else float(radius)
        xy = np.asarray(xy, float).reshape(-1, 2)
        known = self.by_class.get(cls)
        if not known:
            return np.zeros(len(xy), bool)
        k = np.asarray(known, float)
        d2 = ((xy[:, None, :] - k[None, :, :]) ** 2).sum(axis=2)
        return (d2 < r * r).any(axis=1)

    def add(self, p: Place) -> bool:
        """Count the place `p`; True when it is distinct (and so kept)."""
        cls, x, y = p
        if self.near(cls, [(x, y)])[0]:
            return False
        self.by_class.setdefault(cls, []).append((float(x), float(y)))
        return True

    def state_dict(self) -> dict:
        return {"radius": self.radius, "by_class": {k: [list(p) for p in v] for k, v in self.by_class.items()}}

    @classmethod
    def from_state(cls, d: dict) -> "DistinctPlaces":
        out = cls(d["radius"])
        out.by_class = {k: [tuple(p) for p in v] for k, v in d["by_class"].items()}
        return out


def distinct_flags(places: Iterable[Place], radius: float = PRIMARY_RADIUS_M) -> List[bool]:
    """For places in job order: whether each is distinct."""
    seen = DistinctPlaces(radius)
    return [seen.add(p) for p in places]


def count_distinct(places: Iterable[Place], radius: float = PRIMARY_RADIUS_M) -> int:
    return sum(distinct_flags(places, radius))
