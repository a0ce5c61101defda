"""The paper's difficulty proxy, eq. 3, every term kept on its own (no ROS imports).

    d = w_vis * vis + (w_yaw / N_path) * sum_i psi_dot_i^2 + PLR^2

- vis in [-1, 1]: how visible the obstacles were. The worker reports, per obstacle instance, its
  largest pixel count in any one camera frame over the run divided by `visibility_full_px` (100
  px) and capped at 1, or -1 if it was not placed. vis = 2 * mean(v_i) - 1 over the placed
  non-traversable obstacles: -1 when none was ever seen (or none is placed), +1 when every one
  filled at least 100 px of some frame.
- yaw term: the yaw rate (body-frame angular z, [rad/s]) resampled at N_path = 250 instants evenly
  spread over the run's duration, mean of squares times w_yaw = 10.
- PLR: the driven path length (arc length of the 60 Hz trajectory) over the optimal path length
  from the start to the goal circle with every placed obstacle known (optimal_path.py).

Terminations other than SUCCESS (the paper leaves them open): the vehicle did not reach the goal
circle, so its driven length says too little. The driven length is extended by the straight
distance from where the run ended to the goal circle (a lower bound of what it still had to
drive), so a run that stopped early is never rewarded for stopping, and the termination is kept
in the store so that an analysis can tell collisions and timeouts apart. ERROR is not a scenario
outcome (the stack or the infrastructure failed): it gets no proxy and is not a transition.
"""

import math
from dataclasses import asdict, dataclass
from typing import Optional, Sequence

import numpy as np

from asg_scenario.catalogue import MESHES, TRAVERSABLE_HEIGHT, VEHICLE_HALF_WIDTH
from asg_scenario.report import TERMINATION_NAMES

from asg_agent.scoring.optimal_path import obstacle_discs, shortest_path

#: Every run's ending, in the order of RunScenario.action's codes (one list: asg_scenario.report).
TERMINATIONS = tuple(TERMINATION_NAMES)


@dataclass(frozen=True)
class ProxyConfig:
    """Weights of eq. 3 and the optimal path's clearance."""

    n_path: int = 250  #: [-] samples of the yaw rate (N_path)
    w_vis: float = 0.1  #: [-] weight of vis
    w_yaw: float = 10.0  #: [-] weight of the mean-square yaw rate
    clearance: float = VEHICLE_HALF_WIDTH  #: [m] added to every obstacle's collision radius


@dataclass
class ProxyTerms:
    proxy: float  #: d, eq. 3
    vis: float  #: [-1, 1]
    yaw_term: float  #: (w_yaw / N) sum psi_dot^2
    plr: float  #: path length ratio
    path_length: float  #: [m] driven (plus the straight rest for runs that did not arrive)
    optimal_length: float  #: [m] start to goal circle, all obstacles known
    termination: str

    def as_dict(self):
        return asdict(self)


def visibility_term(scenario: dict, visibility: Sequence[float]) -> float:
    """vis in [-1, 1] from the result's per-instance visibility (flattened layout order)."""
    vals = []
    k = 0
    for layout in scenario["structural"]["layouts"]:
        mesh = MESHES[layout["mesh_name"]]
        for inst in layout["instances"]:
            v = visibility[k] if k < len(visibility) else -1.0
            k += 1
            if v < 0 or mesh.height * inst["scale"] <= TRAVERSABLE_HEIGHT:
                continue
            vals.append(min(1.0, max(0.0, float(v))))
    return 2.0 * float(np.mean(vals)) - 1.0 if vals else -1.0


def yaw_rate_term(t: np.ndarray, yaw_rate: np.ndarray, n_path: int, weight: float) -> float:
    """(weight / n_path) * sum of the squared yaw rate at n_path instants evenly over the run."""
    t = np.asarray(t, dtype=np.float64)
    if len(t) < 2 or t[-1] <= t[0]:
        return 0.0
    ts = np.linspace(t[0], t[-1], n_path)
    r = np.interp(ts, t, np.asarray(yaw_rate, dtype=np.float64))
    return float(weight * np.mean(r * r))


def path_length(xy: np.ndarray) -> float:
    xy = np.asarray(xy, dtype=np.float64)
    return float(np.sum(np.hypot(np.diff(xy[:, 0]), np.diff(xy[:, 1])))) if len(xy) > 1 else 0.0


def resample_path(xy: np.ndarray, n: int) -> np.ndarray:
    """n points evenly spaced by arc length along a polyline (n x 2)."""
    xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    if len(xy) == 0:
        return np.zeros((n, 2))
    seg = np.hypot(np.diff(xy[:, 0]), np.diff(xy[:, 1]))
    s = np.concatenate([[0.0], np.cumsum(seg)])
    if s[-1] <= 0:
        return np.repeat(xy[:1], n, axis=0)
    q = np.linspace(0.0, s[-1], n)
    return np.stack([np.interp(q, s, xy[:, 0]), np.interp(q, s, xy[:, 1])], axis=1)


def placed_mask(scenario: dict, removed) -> list:
    """Per flattened instance, False for those the worker removed; `removed` holds
    (layout, instance[, reason]) entries as results and the store give them."""
    gone = {(int(r[0]), int(r[1])) for r in removed}
    return [
        (li, ii) not in gone
        for li, l in enumerate(scenario["structural"]["layouts"])
        for ii in range(len(l["instances"]))
    ]


def optimal_path(scenario: dict, placed: Optional[Sequence[bool]] = None, config: ProxyConfig = ProxyConfig()):
    """The optimal path (optimal_path.OptimalPath) with every placed obstacle known."""
    op = scenario["operational"]
    discs = obstacle_discs(scenario, config.clearance, placed)
    return shortest_path((op["start_x"], op["start_y"]), (op["goal_x"], op["goal_y"]), op["goal_radius"], discs)


def optimal_length(
    scenario: dict, placed: Optional[Sequence[bool]] = None, config: ProxyConfig = ProxyConfig()
) -> float:
    return optimal_path(scenario, placed, config).length


def compute(
    scenario: dict,
    t,
    xy,
    yaw_rate,
    visibility,
    termination: str,
    placed: Optional[Sequence[bool]] = None,
    config: ProxyConfig = ProxyConfig(),
) -> Optional[ProxyTerms]:
    """Every term of eq. 3 for one run; None for termination ERROR."""
    if termination not in TERMINATIONS:
        raise ValueError(f"termination {termination!r}: one of {', '.join(TERMINATIONS)}")
    if termination == "ERROR":
        return None
    op = scenario["operational"]
    xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    driven = path_length(xy)
    if termination != "SUCCESS" and len(xy):
        rest = math.dist(xy[-1], (op["goal_x"], op["goal_y"])) - op["goal_radius"]
        driven += max(0.0, rest)
    opt = optimal_length(scenario, placed, config)
    if not math.isfinite(opt) or opt <= 1e-9:
        plr = 1.0  # no path exists (or the start is in the goal circle): nothing to compare with
    else:
        plr = driven / opt
    vis = visibility_term(scenario, visibility)
    yaw = yaw_rate_term(t, yaw_rate, config.n_path, config.w_yaw)
    d = config.w_vis * vis + yaw + plr * plr
    return ProxyTerms(d, vis, yaw, plr, driven, opt, termination)


def run_terms(scenario: dict, run, config: ProxyConfig = ProxyConfig(), dtype=np.float32):
    """(trajectory as an N x 5 array of `dtype`, every term of eq. 3) for one finished run: any object
    with `trajectory` (t, x, y, yaw, yaw rate rows), `visibility`, `termination` and `removed`, as the
    worker pool's outcomes are. The terms are None for a run that ended in ERROR or has no samples.
    The campaign scores in float32 (the stored proxies); keep `dtype` when recomputing them."""
    traj = np.asarray(run.trajectory, dtype).reshape(-1, 5)
    if run.termination == "ERROR" or not len(traj):
        return traj, None
    placed = placed_mask(scenario, run.removed)
    return traj, compute(
        scenario, traj[:, 0], traj[:, 1:3], traj[:, 4], run.visibility, run.termination, placed, config
    )


def term_values(terms) -> dict:
    """The proxy and its three terms of `run_terms`' result as plain values (all None for a run
    without terms: an ERROR), as the store, attribution and the re-run files keep them."""
    keys = ("proxy", "vis", "yaw_term", "plr")
    return {k: (getattr(terms, k) if terms else None) for k in keys}
