"""A lattice of constant-curvature arcs: from the vehicle's pose, roll each arc out over the
horizon, drop the arcs that pass closer than `clearance` to an obstacle, and take the one whose
end is nearest the goal (plus small penalties for turning and for changing the arc). Shorter
horizons are tried when every full arc is blocked; with none left, stop. The speed falls with
the clearance left along the chosen arc. No ROS."""

from dataclasses import dataclass
from typing import Optional

import numpy as np


@dataclass
class ArcParams:
    speed: float = 5.0  #: [m/s] cruise speed
    min_speed: float = 1.5  #: [m/s] speed with the least clearance that still passes
    max_curvature: float = 0.25  #: [1/m] sharpest arc (the vehicle's: tan(0.6 rad) / 2.3 m = 0.30)
    arcs: int = 21  #: [-] arcs in the lattice, curvatures evenly spaced, odd so one is straight
    horizon: float = 12.0  #: [m] length of an arc
    step: float = 0.5  #: [m] spacing of the samples along an arc
    clearance: float = 1.6  #: [m] smallest distance from the vehicle's centre line to an obstacle
    slow_clearance: float = 4.0  #: [m] below this clearance along the arc the speed falls
    turn_weight: float = 2.0  #: [m per 1/m] cost of curvature
    change_weight: float = 8.0  #: [m per 1/m] cost of leaving the previous arc

    def check(self):
        if self.arcs < 1 or self.arcs % 2 == 0:
            raise ValueError(f"arc parameter arcs = {self.arcs}: must be odd and >= 1")
        for name in ("speed", "max_curvature", "horizon", "step", "clearance"):
            if not getattr(self, name) > 0:
                raise ValueError(f"arc parameter {name} = {getattr(self, name)}: must be > 0")
        if not 0 <= self.min_speed <= self.speed:
            raise ValueError(f"arc parameter min_speed = {self.min_speed}: must be in [0, speed]")
        return self


@dataclass
class Choice:
    speed: float  #: [m/s]
    yaw_rate: float  #: [rad/s]
    curvature: float  #: [1/m]
    clearance: float  #: [m] smallest along the chosen arc
    blocked: bool  #: every arc blocked: stop


def rollout(x, y, yaw, curvature, length, step):
    """Sample points [m] (K x 2) along an arc of `curvature` from (x, y, yaw)."""
    s = np.arange(step, length + 1e-9, step)
    if abs(curvature) < 1e-9:
        return np.stack([x + s * np.cos(yaw), y + s * np.sin(yaw)], axis=1)
    th = yaw + curvature * s
    return np.stack([x + (np.sin(th) - np.sin(yaw)) / curvature, y - (np.cos(th) - np.cos(yaw)) / curvature], axis=1)


class ArcPlanner:
    def __init__(self, params: ArcParams):
        self.p = params.check()
        self.curvatures = np.linspace(-params.max_curvature, params.max_curvature, params.arcs)
        self.previous = 0.0

    def reset(self):
        self.previous = 0.0

    def choose(self, x, y, yaw, goal, obstacles_xy: Optional[np.ndarray]) -> Choice:
        """The command at pose (x [m], y [m], yaw [rad]) towards `goal` (x, y) [m], with the
        obstacle cells' centres `obstacles_xy` (K x 2, map frame)."""
        obs = np.zeros((0, 2)) if obstacles_xy is None else np.asarray(obstacles_xy, float).reshape(-1, 2)
        reach = self.p.horizon + self.p.clearance
        if len(obs):
            obs = obs[np.hypot(obs[:, 0] - x, obs[:, 1] - y) <= reach]
        goal = np.asarray(goal, float)
        for length in (self.p.horizon, self.p.horizon / 2, self.p.horizon / 4):
            best = None
            for k in self.curvatures:
                pts = rollout(x, y, yaw, k, length, self.p.step)
                if len(obs):
                    d = np.sqrt(((pts[:, None, :] - obs[None, :, :]) ** 2).sum(axis=2)).min()
                else:
                    d = np.inf
                if d < self.p.clearance:
                    continue
                cost = (
                    np.hypot(*(pts[-1] - goal))
                    + self.p.turn_weight * abs(k)
                    + self.p.change_weight * abs(k - self.previous)
                )
                if best is None or cost < best[0]:
                    best = (cost, k, d)
            if best is not None:
                _, k, d = best
                self.previous = float(k)
                span = max(self.p.slow_clearance - self.p.clearance, 1e-9)
                share = np.clip((d - self.p.clearance) / span, 0.0, 1.0)
                v = self.p.min_speed + (self.p.speed - self.p.min_speed) * share
                if length < self.p.horizon:
                    v = self.p.min_speed
                return Choice(float(v), float(v * k), float(k), float(d), False)
        return Choice(0.0, 0.0, 0.0, 0.0, True)
