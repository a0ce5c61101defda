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
- `failure` (issue #78): a stack's own failures, for a stack tested without a reference (a user's
  stack, `attribution:=false`): 1 for a run that failed (a collision, a timeout, a flip, out of
  bounds: asg_scenario.schema.FAILED_TERMINATIONS), else a graded part below GRADED_CAP from how
  close it came to an obstacle, GRADED_CAP x (1 - c / CLEARANCE_RANGE); nothing for an ERROR.

All distances are read at 10 Hz (every 6th sample of the 60 Hz trajectory, as attribution keeps a
reference run's positions), so the stack under test and a reference are measured alike.
"""

from dataclasses import dataclass
from typing import Callable, Dict, Optional, Sequence, Tuple

import numpy as np

from asg_agent.scoring.attribution import FINDING as PROXY_FINDING  # [-] the paper's finding: proxy >= 3

DENSE_WEIGHT = 2.0  # [-] contact adds this: a collision on a route of PLR about 1 scores about 3
CLEARANCE_RANGE = 5.0  # [m] clearances at or beyond this add nothing
TTC_RANGE = 3.0  # [s] times to collision at or beyond this add nothing
GRADED_CAP = 0.5  # [-] the `flaw` reward's graded part stays below a finding's 1
CLASS_FINDING = 1.0  # [-] the `flaw` and `regression` rewards of a finding of their class
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
        return CLASS_FINDING
    if full_termination != "SUCCESS" or full_proxy is None:
        return 0.0
    dp = min(max(proxy - full_proxy, 0.0), PROXY_RANGE) / PROXY_RANGE
    c, cf = min(clearance, CLEARANCE_RANGE), min(full_clearance, CLEARANCE_RANGE)
    dc = max(cf - c, 0.0) / CLEARANCE_RANGE
    return GRADED_CAP * 0.5 * (dp + dc) * (1.0 - 1e-9)


def failure_reward(termination: str, clearance: float) -> float:
    """The `failure` reward of a run (see the module's text): its termination and its smallest
    clearance [m] to an obstacle's disc."""
    from asg_scenario.schema import FAILED_TERMINATIONS

    if termination in FAILED_TERMINATIONS:
        return CLASS_FINDING
    return GRADED_CAP * (1.0 - min(clearance, CLEARANCE_RANGE) / CLEARANCE_RANGE) * (1.0 - 1e-9)


def collision_reward(proxy: float, termination: str, reference_termination: Optional[str], bonus: float) -> float:
    """The "collision" reward: the proxy, plus `bonus` [-] when the stack under test collided and
    the reference stack (where there is one) reached the goal on the same scene: a perception
    collision as every count of the project defines it, which the proxy alone scores like any
    run that ended early."""
    collided = termination == "COLLISION" and reference_termination in (None, "SUCCESS")
    return proxy + (bonus if collided else 0.0)


# -- the registry: what a campaign can maximise, each with what it needs (issue #69) -------------


@dataclass(frozen=True)
class Run:
    """The stack under test's run of a scenario, as a reward reads it: its proxy (None when it
    has none), termination, request, 10 Hz positions [m] and removed obstacles."""

    proxy: Optional[float]
    termination: str
    request: dict
    xy: np.ndarray
    removed: Sequence = ()


@dataclass(frozen=True)
class Reward:
    """A reward (`Campaign`'s `reward`): `own(run, bonus)` its value from the stack under test's
    run alone (None without a proxy); `attached(run, refs, cls, bonus)` its value once the
    candidate's reference runs are in (refs: role -> the stored reference run; cls: attribution's
    class), None to keep `own`'s. `waits`: the search waits for the references of a candidate
    (rewards that read them); `roles`: the reference roles it needs; `any_reference`: it needs one,
    whichever; `every_scenario`: every scenario must be re-run (candidates 'all'); `finding_at`: a
    scenario whose reward is at least this is one of the campaign's findings (issue #78: what its
    distinct findings count, and what a search that avoids known places is told)."""

    name: str
    own: Callable
    attached: Optional[Callable] = None
    waits: bool = False
    roles: Tuple[str, ...] = ()
    any_reference: bool = False
    every_scenario: bool = False
    finding_at: float = PROXY_FINDING


def _truth_or_release(refs):
    from asg_agent.scoring import attribution as attr

    return refs.get(attr.TRUTH) or refs.get(attr.RELEASE)


def _differential(run, refs, cls, bonus):
    t = _truth_or_release(refs)
    return run.proxy - t["proxy"] if run.proxy is not None and t and t["proxy"] is not None else None


def _collision_attached(run, refs, cls, bonus):
    if run.proxy is None:
        return None
    return collision_reward(run.proxy, run.termination, _truth_or_release(refs)["termination"], bonus)


def _regret(run, refs, cls, bonus):
    from asg_agent.scoring import attribution as attr

    full = refs[attr.FULL]
    if run.proxy is None or full["proxy"] is None:
        return None
    ref_xy = np.asarray(full["trajectory_xy"])
    return regret_reward(
        run.proxy,
        min_clearance(run.request, run.xy, run.removed),
        full["proxy"],
        min_clearance(run.request, ref_xy, run.removed),
    )


def _class_reward(target: str, role: str):
    def attached(run, refs, cls, bonus):
        clean = refs[role]
        if run.proxy is None:
            return None
        return flaw_reward(
            cls,
            run.proxy,
            min_clearance(run.request, run.xy, run.removed),
            clean["termination"],
            clean["proxy"],
            min_clearance(run.request, np.asarray(clean["trajectory_xy"]), run.removed),
            target=target,
        )

    return attached


def _registry() -> Dict[str, Reward]:
    from asg_agent.scoring import attribution as attr

    def proxy(run, bonus):
        return run.proxy

    return {
        r.name: r
        for r in (
            Reward("proxy", proxy),
            Reward("differential", proxy, _differential, waits=True, any_reference=True, every_scenario=True),
            Reward(
                "collision",
                lambda run, bonus: collision_reward(run.proxy, run.termination, None, bonus),
                _collision_attached,
                waits=True,
            ),
            Reward(
                "clearance",
                lambda run, bonus: clearance_reward(run.proxy, min_clearance(run.request, run.xy, run.removed)),
            ),
            Reward(
                "ttc", lambda run, bonus: ttc_reward(run.proxy, min_time_to_collision(run.request, run.xy, run.removed))
            ),
            Reward("regret", proxy, _regret, waits=True, roles=(attr.FULL,), every_scenario=True),
            Reward(
                "failure",
                lambda run, bonus: failure_reward(run.termination, min_clearance(run.request, run.xy, run.removed)),
                finding_at=CLASS_FINDING,
            ),
            Reward(
                "flaw",
                lambda run, bonus: NON_CANDIDATE_FLAW,
                _class_reward("flaw", attr.FULL),
                waits=True,
                roles=(attr.FULL,),
                finding_at=CLASS_FINDING,
            ),
            Reward(
                "regression",
                lambda run, bonus: NON_CANDIDATE_FLAW,
                _class_reward("regression", attr.RELEASE),
                waits=True,
                roles=(attr.RELEASE,),
                finding_at=CLASS_FINDING,
            ),
        )
    }


#: every reward by name, in the order the campaign's --reward lists them
REGISTRY: Dict[str, Reward] = _registry()
REWARDS = tuple(REGISTRY)

#: `--reward auto`: the reward the attribution in use can see (train.launch's default, issue #67)
AUTO = "auto"


def for_roles(roles: Sequence[str]) -> str:
    """The reward `auto` stands for, given the roles of the campaign's references: `flaw` with the
    unflawed stack's re-runs (three-stack attribution; the flaw study v3's winner), `regression`
    with a release's (a stack pair), else `failure`, the stack's own failures (no reference, or
    ground truth alone, which classes no flaw; issue #78: the paper's proxy, round 6's choice
    here, does not see failures)."""
    from asg_agent.scoring import attribution as attr

    if attr.FULL in roles:
        return "flaw"
    if attr.RELEASE in roles:
        return "regression"
    return "failure"
