"""Dense rewards that see failures (issue #37; no ROS): what the search maximises besides the paper's
proxy, which scores a collision like any short run.

- `clearance`: the proxy plus DENSE_WEIGHT x (1 - c / CLEARANCE_RANGE), c the smallest distance
  [m] between the vehicle's reference point and a placed obstacle's collision disc over the run
  (0 on contact), capped at CLEARANCE_RANGE: the closer the vehicle came, the more;
- `ttc`: the proxy plus DENSE_WEIGHT x (1 - T / TTC_RANGE), T the smallest time to collision [s]
  over the run: at each position, how long the vehicle would take, at its speed and on its
  heading, to reach an obstacle's disc (0 on contact), capped at TTC_RANGE;
- `regret`: against the unflawed `full` stack on the same scene (every scenario re-run on it):
  proxy - full's proxy + DENSE_WEIGHT x (c_full - c) / CLEARANCE_RANGE, the clearances capped as
  above: what the flaw costs, in the paper's score and in how close the vehicle came.
- `flaw` (issue #67): what the search for the injected flaw is scored on, from the candidates'
  re-runs that three-stack attribution makes anyway (no extra run): 1 for a `flaw` finding (only
  the stack under test fails); for another candidate on which the unflawed `full` stack reached
  the goal, a graded part below GRADED_CAP, half from how much higher the stack under test's proxy
  was (capped at PROXY_RANGE) and half from how much closer it came to an obstacle than `full`
  did (capped at CLEARANCE_RANGE); 0 for a candidate on which `full` failed too (the layout
  exposes what both share, not the flaw). A non-candidate (the stack under test reached the goal
  with proxy below attribution.CANDIDATE) is NON_CANDIDATE_FLAW: it showed nothing of a failure.
- `regression` (issue #67): the same for a stack pair (attribution's `release` role): 1 for a
  `regression` (only the stack under test fails), graded against the release's run, 0 otherwise.

All distances are read at 10 Hz (every 6th sample of the 60 Hz trajectory, as attribution keeps a
reference run's positions), so the stack under test and a reference are measured alike.
"""

from typing import Optional, Sequence

import numpy as np

DENSE_WEIGHT = 2.0  # [-] contact adds this: a collision on a route of PLR about 1 scores about 3
CLEARANCE_RANGE = 5.0  # [m] clearances at or beyond this add nothing
TTC_RANGE = 3.0  # [s] times to collision at or beyond this add nothing
GRADED_CAP = 0.5  # [-] the `flaw` reward's graded part stays below a finding's 1
PROXY_RANGE = 2.0  # [-] proxy differences beyond this add nothing to the graded part
NON_CANDIDATE_FLAW = 0.0  # [-] the `flaw` reward of a scenario not re-run on the references
SAMPLE_EVERY = 6  # [samples] 60 Hz -> 10 Hz
SAMPLE_DT = SAMPLE_EVERY / 60.0  # [s]


def _discs(request: dict, removed) -> np.ndarray:
    from asg_agent.scoring.optimal_path import obstacle_discs
    from asg_agent.scoring.proxy import placed_mask

    d = obstacle_discs(request, 0.0, placed_mask(request, removed or []))
    return np.array([(c.x, c.y, c.r) for c in d], float).reshape(-1, 3)


def min_clearance(request: dict, xy: np.ndarray, removed: Optional[Sequence] = None) -> float:
    """[m] smallest distance from the 10 Hz positions `xy` (n x 2) to a placed obstacle's
    collision disc, 0 inside one; CLEARANCE_RANGE when there is no obstacle or no position."""
    discs, xy = _discs(request, removed), np.asarray(xy, float).reshape(-1, 2)
    if not len(discs) or not len(xy):
        return CLEARANCE_RANGE
    gap = np.hypot(xy[:, None, 0] - discs[None, :, 0], xy[:, None, 1] - discs[None, :, 1]) - discs[None, :, 2]
    return float(min(CLEARANCE_RANGE, max(0.0, gap.min())))


def min_time_to_collision(request: dict, xy: np.ndarray, removed: Optional[Sequence] = None) -> float:
    """[s] smallest time to collision over the 10 Hz positions `xy`: from each position, moving at
    its speed along its heading (both from the next position), the time to enter an obstacle's
    disc; TTC_RANGE when none is reached within it."""
    discs, xy = _discs(request, removed), np.asarray(xy, float).reshape(-1, 2)
    if not len(discs) or len(xy) < 2:
        return TTC_RANGE
    v = np.diff(xy, axis=0) / SAMPLE_DT  # [m/s]
    p = xy[:-1]
    speed = np.linalg.norm(v, axis=1)
    best = TTC_RANGE
    for cx, cy, r in discs:
        rel = p - (cx, cy)
        inside = np.hypot(rel[:, 0], rel[:, 1]) <= r
        if inside.any():
            return 0.0
        # |rel + v t| = r: a t^2 + b t + c = 0, the earliest t >= 0
        a = (v * v).sum(axis=1)
        b = 2.0 * (rel * v).sum(axis=1)
        c = (rel * rel).sum(axis=1) - r * r
        disc = b * b - 4.0 * a * c
        ok = (speed > 1e-6) & (disc >= 0.0)
        t = np.where(ok, (-b - np.sqrt(np.where(ok, disc, 0.0))) / (2.0 * np.where(ok, a, 1.0)), np.inf)
        t = t[(t >= 0.0)]
        if t.size:
            best = min(best, float(t.min()))
    return best


def clearance_reward(proxy: float, clearance: float) -> float:
    return proxy + DENSE_WEIGHT * (1.0 - min(clearance, CLEARANCE_RANGE) / CLEARANCE_RANGE)


def ttc_reward(proxy: float, ttc: float) -> float:
    return proxy + DENSE_WEIGHT * (1.0 - min(ttc, TTC_RANGE) / TTC_RANGE)


def regret_reward(proxy: float, clearance: float, full_proxy: float, full_clearance: float) -> float:
    c, cf = min(clearance, CLEARANCE_RANGE), min(full_clearance, CLEARANCE_RANGE)
    return proxy - full_proxy + DENSE_WEIGHT * (cf - c) / CLEARANCE_RANGE


def flaw_reward(
    cls: str,
    proxy: float,
    clearance: float,
    full_termination: str,
    full_proxy: Optional[float],
    full_clearance: float,
    target: str = "flaw",
) -> float:
    """The `flaw` reward of a candidate (see the module's text): `cls` its attribution class,
    proxy and clearance [m] of the stack under test's run, and the `full` reference run's. The
    `regression` reward of a stack pair is the same with target "regression" and the `release`
    reference's run in place of `full`'s."""
    if cls == target:
        return 1.0
    if full_termination != "SUCCESS" or full_proxy is None:
        return 0.0
    dp = min(max(proxy - full_proxy, 0.0), PROXY_RANGE) / PROXY_RANGE
    c, cf = min(clearance, CLEARANCE_RANGE), min(full_clearance, CLEARANCE_RANGE)
    dc = max(cf - c, 0.0) / CLEARANCE_RANGE
    return GRADED_CAP * 0.5 * (dp + dc) * (1.0 - 1e-9)
