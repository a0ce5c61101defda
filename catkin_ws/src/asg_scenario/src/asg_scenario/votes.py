"""Where a planner's votes fell, judged against the scene (no rospy): votes no obstacle explains,
and votes that lie in an obstacle's sun shadow (the perception flaw of the paper)."""

import math
from typing import Iterable, List, Set, Tuple

from .catalogue import MESHES

#: A sun lower than this is lit as at this inclination (as the renderer does).
MIN_SUN_DEG = 5.0


def _placed(scenario: dict, removed: Set[Tuple[int, int]]):
    for li, layout in enumerate(scenario["structural"]["layouts"]):
        mesh = MESHES[layout["mesh_name"]]
        for ii, inst in enumerate(layout["instances"]):
            if inst["visible"] and (li, ii) not in removed:
                yield mesh, inst


def _unexplained(scenario, votes, cell, removed) -> List[dict]:
    obstacles = [(i["x"], i["y"], m.collision_radius * i["scale"]) for m, i in _placed(scenario, removed)]
    return [v for v in votes if all(math.hypot(v["x"] - x, v["y"] - y) > r + cell for x, y, r in obstacles)]


def phantom_votes(
    scenario: dict, votes: Iterable[dict], cell: float, removed: Set[Tuple[int, int]] = frozenset()
) -> int:
    """Voted vertices with no placed obstacle within its collision radius plus one vote cell:
    votes that only a perception error can have cast. votes: dicts with x, y [m]; removed:
    (layout, instance) pairs the worker did not place."""
    return len(_unexplained(scenario, list(votes), cell, removed))


def _shadows(scenario: dict, removed: Set[Tuple[int, int]]):
    """(dx, dy, [(x, y, length, radius)]): the direction along every shadow (away from the sun)
    and each shadow-casting obstacle's foot [m], shadow length [m] and radius at its foot [m]."""
    tex = scenario["textural"]
    inc = math.radians(max(float(tex["sun_inclination_deg"]), MIN_SUN_DEG))
    yaw = math.radians(float(tex["sun_yaw_deg"]))
    casters = [
        (inst["x"], inst["y"], mesh.height * inst["scale"] / math.tan(inc), mesh.collision_radius * inst["scale"])
        for mesh, inst in _placed(scenario, removed)
        if inst["cast_shadow"]
    ]
    return -math.cos(yaw), -math.sin(yaw), casters


def in_cast_shadow(
    scenario: dict, x: float, y: float, margin: float = 0.0, removed: Set[Tuple[int, int]] = frozenset()
) -> bool:
    """Whether ground point (x, y) lies in the sun shadow of a shadow-casting obstacle: the
    shadow of a conifer-like shape, a strip from the obstacle's foot away from the sun, as long
    as height / tan(inclination) and as wide as the obstacle at its foot, narrowing to its
    tip; margin widens it."""
    dx, dy, casters = _shadows(scenario, removed)
    for ox, oy, length, radius in casters:
        px, py = x - ox, y - oy
        t = px * dx + py * dy
        if 0.0 <= t <= length and abs(px * dy - py * dx) <= radius * (1.0 - t / length) + margin:
            return True
    return False


def shadow_mask(scenario: dict, xs, ys, removed: Set[Tuple[int, int]] = frozenset()):
    """in_cast_shadow (margin 0) of many ground points at once: a boolean array shaped as xs.
    The same arithmetic in the same order, element by element, so the same answer point by
    point (test_votes.py compares them); numpy, for the callers that ask about a grid of points
    (asg_agent.records.scenes.shadow_ahead)."""
    import numpy as np

    xs, ys = np.asarray(xs, dtype=float), np.asarray(ys, dtype=float)
    out = np.zeros(xs.shape, dtype=bool)
    dx, dy, casters = _shadows(scenario, removed)
    for ox, oy, length, radius in casters:
        px, py = xs - ox, ys - oy
        t = px * dx + py * dy
        out |= (0.0 <= t) & (t <= length) & (np.abs(px * dy - py * dx) <= radius * (1.0 - t / length) + 0.0)
    return out


def shadow_votes(
    scenario: dict, votes: Iterable[dict], cell: float, removed: Set[Tuple[int, int]] = frozenset()
) -> int:
    """Phantom voted vertices (see phantom_votes) that lie in an obstacle's cast shadow (half a
    cell of margin): obstacles a segmenter saw in a shadow."""
    return sum(
        1
        for v in _unexplained(scenario, list(votes), cell, removed)
        if in_cast_shadow(scenario, v["x"], v["y"], cell / 2, removed)
    )
