"""Measures over a campaign's exported rows that the tables and figures of docs/experiments.md
share: rates, curves of findings, distances between layouts and distinct findings, terrain and
weather attributes of a scenario (the scenario request of a row: asg_agent.records.scenes). No ROS."""

from typing import Dict, List, Optional

import numpy as np

from asg_agent.records.store import FINDING
from asg_agent.scoring import attribution as attribution_rule

PAPER = {"exp1": (682, 138, 8.31), "exp2": (126, 7, 6.79), "exp3": (477, 82, 6.67), "exp4": (305, 67, 8.00)}
PAPER_SCENARIOS = 5000


def active_hours(rows) -> float:
    """Wall time of a campaign from its rows' finish times, gaps over 5 minutes (a campaign
    stopped and resumed later) left out; None when the export predates the field."""
    t = sorted(r["finished"] for r in rows if r.get("finished"))
    if len(t) < 2:
        return None
    gaps = np.diff(t)
    return float(gaps[gaps < 300].sum() + np.median(gaps)) / 3600.0


def ge3_curve(rows, budget: int) -> np.ndarray:
    """Count of proxy >= 3 after each scenario, in job order, up to the budget."""
    rows = sorted(rows, key=lambda r: r["job"])[:budget]
    return np.cumsum([(r["proxy"] or 0) >= FINDING for r in rows])


def layout_distance(a, b, meshes) -> float:
    """[m] mean displacement between two layouts with obstacles matched one to one within each
    type (mesh) so that the total displacement is least (Hungarian assignment)."""
    from scipy.optimize import linear_sum_assignment

    a, b = np.asarray(a, float), np.asarray(b, float)
    total = 0.0
    for m in sorted(set(meshes)):
        idx = [i for i, x in enumerate(meshes) if x == m]
        d = np.linalg.norm(a[idx][:, None, :] - b[idx][None, :, :], axis=2)
        r, c = linear_sum_assignment(d)
        total += d[r, c].sum()
    return total / len(meshes)


def layout_distances(a, others, meshes) -> np.ndarray:
    """layout_distance from layout `a` to each layout of `others` (K x N x 2) at once: exact,
    by trying every matching within a type where a type has at most 6 obstacles, by the
    Hungarian assignment per layout otherwise."""
    import itertools

    a, others = np.asarray(a, float), np.asarray(others, float).reshape(-1, len(meshes), 2)
    total = np.zeros(len(others))
    for m in sorted(set(meshes)):
        idx = [i for i, x in enumerate(meshes) if x == m]
        d = np.linalg.norm(others[:, idx][:, :, None, :] - a[idx][None, None, :, :], axis=3)  # K x n(other) x n(a)
        if len(idx) <= 6:
            perms = np.array(list(itertools.permutations(range(len(idx)))))
            total += d[:, np.arange(len(idx))[None, :], perms].sum(axis=2).min(axis=1)
        else:
            from scipy.optimize import linear_sum_assignment

            for k in range(len(others)):
                r, c = linear_sum_assignment(d[k])
                total[k] += d[k][r, c].sum()
    return total / len(meshes)


def _is_new(rows, threshold: float) -> List[bool]:
    """In the given order: whether each row's layout is farther than `threshold` metres
    (layout_distance) from every earlier new one."""
    kept, new = [], []
    for r in rows:
        p = np.asarray(r["positions"], float)
        new.append(not kept or bool(layout_distances(p, kept, r["meshes"]).min() > threshold))
        if new[-1]:
            kept.append(p)
    return new


def distinct(rows, top: Optional[int], threshold: float, min_proxy: float = -np.inf) -> int:
    """Distinct layouts among the `top` highest-proxy rows (all of them when `top` is None) with
    proxy >= `min_proxy`, taken in rank order (_is_new)."""
    ranked = sorted((r for r in rows if r["proxy"] is not None and r["proxy"] >= min_proxy), key=lambda r: -r["proxy"])[
        :top
    ]
    return sum(_is_new(ranked, threshold))


def distinct_curve(rows, budget: int, threshold: float, min_proxy: float = FINDING, pred=None) -> np.ndarray:
    """Count of distinct finds after each scenario, in job order up to the budget: the
    scenarios with proxy >= `min_proxy` (or for which `pred(row)` holds) taken in the order
    found (_is_new)."""
    rows = sorted(rows, key=lambda r: r["job"])[:budget]
    pred = pred or (lambda r: (r["proxy"] or 0) >= min_proxy)
    finds = [r for r in rows if pred(r)]
    new = dict(zip((id(r) for r in finds), _is_new(finds, threshold)))
    return np.cumsum([new.get(id(r), False) for r in rows]).astype(int)


# Round 3's single-reference predicates live with the rule (scoring/attribution.py).
_perception_finding = attribution_rule.perception_finding
_differential = attribution_rule.differential_finding
_perception_collision = attribution_rule.perception_collision


def _ref(r):
    return r.get("reference") or {}


def elapsed_hours(rows, budget: int) -> np.ndarray:
    """[h] active wall time after each scenario in job order (active_hours' rule: gaps over 5
    minutes, a campaign stopped and resumed, left out); None when the export has no times."""
    rows = sorted(rows, key=lambda r: r["job"])[:budget]
    t = np.array([r.get("finished") or np.nan for r in rows], float)
    if np.isnan(t).any() or len(t) < 2:
        return None
    order = np.maximum.accumulate(t)  # rows finish out of job order; time spent is the latest finish
    gaps = np.diff(order, prepend=order[0])
    med = float(np.median(gaps[1:][gaps[1:] > 0])) if (gaps[1:] > 0).any() else 0.0
    gaps[0] = med  # the first scenario took about what a typical one takes
    return np.cumsum(np.where(gaps < 300, gaps, med)) / 3600.0


def _segment_distance_xy(px, py, ax, ay, bx, by) -> float:
    dx, dy = bx - ax, by - ay
    t = 0.0 if dx == dy == 0 else max(0.0, min(1.0, ((px - ax) * dx + (py - ay) * dy) / (dx * dx + dy * dy)))
    return float(np.hypot(px - ax - t * dx, py - ay - t * dy))


#: Issue #27: scene attributes of the terrain, from an export row's `terrain` (flat: absent)
TERRAIN_ATTRIBUTES = {
    "amplitude_m": lambda t, row: float(t.get("amplitude_m", 0.0)),
    "highest_hill_m": lambda t, row: max([h["height_m"] for h in t.get("hills", [])] or [0.0]),
    "deepest_ditch_m": lambda t, row: max([-h["height_m"] for h in t.get("hills", [])] or [0.0]),
    # [m] the nearest hill or ditch of at least 1 m to the straight start-goal line, from its rim
    "hill_from_route_m": lambda t, row: min(
        [
            _segment_distance_xy(h["x"], h["y"], *row["_route"]) - h["radius_m"]
            for h in t.get("hills", [])
            if abs(h["height_m"]) >= 1.0
        ]
        or [np.inf]
    ),
}


def attribute_value(row: dict, attr: str, route=(20.0, 20.0, 80.0, 80.0)) -> float:
    """A scene attribute of an export row: a textural one by name, or `terrain.NAME` of
    TERRAIN_ATTRIBUTES (route: start x, y and goal x, y of the experiment)."""
    if attr.startswith("terrain."):
        return TERRAIN_ATTRIBUTES[attr[len("terrain.") :]](row.get("terrain") or {}, dict(row, _route=route))
    return float(row["textural"][attr])


def obstacles_hit(rows) -> Dict[str, dict]:
    """Collisions of the stack under test by the mesh of the obstacle hit (the export's
    `collision_with`, an index into `meshes`); {} for exports made before it was exported."""
    out: Dict[str, dict] = {}
    for r in rows:
        if r["termination"] != "COLLISION" or r.get("collision_with") is None:
            continue
        c = out.setdefault(r["meshes"][r["collision_with"]], {"collisions": 0, "perception_collisions": 0})
        c["collisions"] += 1
        c["perception_collisions"] += int(_perception_collision(r))
    return dict(sorted(out.items(), key=lambda kv: -kv[1]["collisions"]))


def fmt(v, spec=".2f"):
    return "-" if v is None else format(v, spec)
