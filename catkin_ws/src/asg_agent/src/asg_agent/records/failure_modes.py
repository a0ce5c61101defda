"""Failure modes (issue #37; no ROS): what kind of failure a finding is, so that findings can be
counted distinct and a search's coverage of the failure space measured, as the self-driving tool
competitions count failures by the cells of a feature map they fill.

A failure's mode is one cell of four features, all read from an export row (its request's
obstacles, its 10 Hz positions, the obstacle it hit):

- `obstacle`: the mesh of the obstacle hit (`juniper`, `barberry`, ...), or `none` for a failure
  without a collision (a timeout, or proxy >= 3 at the goal);
- `along`: where along the straight start-goal route the failure happened, in ROUTE_BINS equal
  parts (the failure point projected on the route: the last position of a run that ended early,
  otherwise the position farthest from the route);
- `side`: on which side of the route the obstacle hit stands, seen from the start (`left`,
  `right`, or `on` within ON_ROUTE of it); `none` without a collision;
- `shadow`: whether an obstacle's cast shadow lay in the corridor ahead of the vehicle (20 m
  ahead, 5 m to either side) SHADOW_LEAD before the failure point (`shadow` / `lit`): the
  flaw's trigger, ground in shadow taken for an obstacle.

Two findings are the same failure mode when they fall in the same cell; `coverage` is the share
of the cells a set of findings fills, out of `cells(meshes)`.
"""

from typing import Iterable, List, Sequence, Tuple

import numpy as np

ROUTE_BINS = 4  # [-] parts of the start-goal route
ON_ROUTE = 1.0  # [m] an obstacle this close to the route's line is on it
SHADOW_LEAD = 2.0  # [s] how long before the failure point the corridor ahead is looked at
POSITIONS_HZ = 10.0  # [Hz] the export's trajectory_xy rate
SIDES = ("left", "on", "right")


def failure_point(xy: np.ndarray, a: np.ndarray, b: np.ndarray, ended_early: bool) -> int:
    """Index of the failure point in `xy`: the last one of a run that ended early, otherwise the
    one farthest from the straight route a-b."""
    if ended_early or len(xy) < 2:
        return len(xy) - 1
    ab = b - a
    d = np.abs(ab[0] * (xy[:, 1] - a[1]) - ab[1] * (xy[:, 0] - a[0])) / max(np.linalg.norm(ab), 1e-9)
    return int(np.argmax(d))


def mode(row: dict, request: dict) -> Tuple[str, int, str, str]:
    """The failure-mode cell (obstacle, along, side, shadow) of an export row and its request."""
    from asg_agent.records.scenes import shadow_ahead

    op = request["operational"]
    a, b = np.array([op["start_x"], op["start_y"]], float), np.array([op["goal_x"], op["goal_y"]], float)
    xy = np.asarray(row["trajectory_xy"], float).reshape(-1, 2)
    i = failure_point(xy, a, b, row["termination"] != "SUCCESS")
    ab = b - a
    t = float(np.clip(((xy[i] - a) @ ab) / (ab @ ab), 0.0, 1.0 - 1e-9))
    along = int(t * ROUTE_BINS)
    hit = row.get("collision_with")
    if row["termination"] == "COLLISION" and hit is not None:
        obstacle = str(row["meshes"][hit])
        p = np.asarray(row["positions"][hit], float)
        cross = ab[0] * (p[1] - a[1]) - ab[1] * (p[0] - a[0])
        offset = cross / max(np.linalg.norm(ab), 1e-9)  # [m] > 0: left of the route seen from the start
        side = "on" if abs(offset) < ON_ROUTE else ("left" if offset > 0 else "right")
    else:
        obstacle, side = "none", "none"
    lead = max(0, i - int(round(SHADOW_LEAD * POSITIONS_HZ)))
    shadow = "shadow" if shadow_ahead(request, xy, lead) else "lit"
    return obstacle, along, side, shadow


def cells(meshes: Sequence[str]) -> int:
    """How many cells the feature map has for obstacles of these meshes: each mesh with the three
    sides, plus `none` with its one side, times ROUTE_BINS, times shadow or lit."""
    return (len(set(meshes)) * len(SIDES) + 1) * ROUTE_BINS * 2


def distinct(modes: Iterable[tuple]) -> int:
    return len(set(modes))


def coverage(modes: Iterable[tuple], meshes: Sequence[str]) -> float:
    return distinct(modes) / cells(meshes)


def modes_of(campaign: dict, rows: List[dict], keep=lambda r: True) -> List[tuple]:
    """The failure modes of the rows of an export that `keep` picks (e.g. its flaw findings)."""
    from asg_agent.records.scenes import scenario_of

    return [mode(r, scenario_of(campaign, r)) for r in rows if keep(r)]


def mode_of_stored(row) -> Tuple[str, int, str, str]:
    """The failure mode of a store row (records/store.py's scenarios table)."""
    import json

    from asg_agent.records.export import collision_index
    from asg_agent.records.store import unpack_trajectory

    req = json.loads(row["request"])
    flat = [(l["mesh_name"], (i["x"], i["y"])) for l in req["structural"]["layouts"] for i in l["instances"]]
    xy = unpack_trajectory(row["trajectory"])[::6, 1:3]
    export_row = {
        "termination": row["termination"],
        "collision_with": collision_index(req, row["collision_with"]),
        "trajectory_xy": xy.tolist(),
        "positions": [list(p) for _, p in flat],
        "meshes": [m for m, _ in flat],
    }
    return mode(export_row, req)


def label(m: Tuple[str, int, str, str]) -> str:
    """A failure mode in words, e.g. 'juniper, 2nd quarter of the route, left, shadow ahead'."""
    obstacle, along, side, shadow = m
    quarter = ("1st", "2nd", "3rd", "4th")[along] if ROUTE_BINS == 4 else f"part {along + 1}"
    where = f"{quarter} quarter of the route"
    hit = (
        "no collision"
        if obstacle == "none"
        else f"{obstacle} on the {side}"
        if side != "on"
        else f"{obstacle} on the route"
    )
    return f"{hit}, {where}, {'shadow' if shadow == 'shadow' else 'no shadow'} ahead"
