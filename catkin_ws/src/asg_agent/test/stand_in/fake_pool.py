"""An in-process stand-in for the worker pool (tests, no ROS, no simulator; not installed).

It "drives" the optimal path with a lateral wiggle that grows near obstacles, so proxies vary
with the layout, and returns results out of order after a seeded random number of polls, like
real workers of uneven speed. Everything is a function of the request: the same request gives
the same outcome, whichever fake worker runs it.
"""

import math
from typing import Dict, List

import numpy as np

from asg_agent.campaign.dispatch import Outcome, Pool
from asg_agent.scoring.optimal_path import obstacle_discs, shortest_path
from asg_agent.scoring.proxy import resample_path
from asg_scenario.catalogue import VEHICLE_HALF_WIDTH


def fake_run(request: dict, gain: float = 0.8) -> Outcome:
    op = request["operational"]
    discs = obstacle_discs(request, VEHICLE_HALF_WIDTH)  # [m] the catalogue's (issue #80: it was a literal)
    path = shortest_path((op["start_x"], op["start_y"]), (op["goal_x"], op["goal_y"]), op["goal_radius"], discs)
    pts = np.asarray(path.points if path.points else [(op["start_x"], op["start_y"])], np.float64)
    n = max(2, int(path.length / (op["speed"] / 60.0))) if math.isfinite(path.length) else 2
    xy = resample_path(pts, n)
    # A wiggle whose amplitude grows with the number of obstacles near the path.
    near = sum(1 for d in discs if np.min(np.hypot(xy[:, 0] - d.x, xy[:, 1] - d.y)) < 8.0)
    s = np.linspace(0.0, 1.0, n)
    normal = np.array([-(op["goal_y"] - op["start_y"]), op["goal_x"] - op["start_x"]])
    normal /= np.linalg.norm(normal)
    xy = xy + np.outer(gain * near * np.sin(np.pi * s) * np.sin(6 * np.pi * s), normal)
    t = np.arange(n) / 60.0
    yaw = np.unwrap(np.arctan2(np.gradient(xy[:, 1]), np.gradient(xy[:, 0])))
    traj = np.stack([t, xy[:, 0], xy[:, 1], yaw, np.gradient(yaw, t) if n > 1 else 0 * t], axis=1)
    vis = [
        1.0 if math.hypot(i["x"] - 50, i["y"] - 50) < 40 else 0.3
        for l in request["structural"]["layouts"]
        for i in l["instances"]
    ]
    term = "SUCCESS" if math.isfinite(path.length) else "STUCK_TIMEOUT"
    return Outcome(
        job=-1,
        worker="",
        termination=term,
        sim_time=float(t[-1]),
        num_control_msgs=int(t[-1] * 20),
        trajectory=traj.astype(np.float32),
        visibility=vis,
    )


class FakePool(Pool):
    def __init__(
        self, workers: int = 2, seed: int = 0, fail_jobs=(), gain: float = 0.8, prefix: str = "fake", collide_jobs=()
    ):
        self.names = [f"/{prefix}_{i}" for i in range(workers)]
        self.gain = gain  # the stand-in stack's wiggle near obstacles (a "worse" stack: larger)
        self.busy: Dict[str, tuple] = {}
        self.rng = np.random.default_rng(seed)
        self.fail_jobs = set(fail_jobs)  # these jobs answer ERROR on their first attempt
        self.collide_jobs = set(collide_jobs)  # these jobs end halfway as a COLLISION with obstacle 0:0
        self.failed_once = set()
        self.submitted: List[int] = []

    def free(self):
        return [w for w in self.names if w not in self.busy]

    def submit(self, worker, job, request):
        self.submitted.append(job)
        self.busy[worker] = (job, request, int(self.rng.integers(0, 4)))

    def poll(self, timeout):
        out = []
        for w in list(self.busy):
            job, request, left = self.busy[w]
            if left > 0:
                self.busy[w] = (job, request, left - 1)
                continue
            del self.busy[w]
            if job in self.fail_jobs and job not in self.failed_once:
                self.failed_once.add(job)
                out.append(Outcome(job=job, worker=w, termination="ERROR", error="planner: fake failure"))
                continue
            o = fake_run(request, self.gain)
            o.job, o.worker = job, w
            if job in self.collide_jobs:
                o.trajectory = o.trajectory[: max(2, len(o.trajectory) // 2)]
                o.termination, o.collision_with, o.sim_time = "COLLISION", "0:0", float(o.trajectory[-1, 0])
            out.append(o)
        return out
