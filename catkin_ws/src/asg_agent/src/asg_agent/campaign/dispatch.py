"""Requests to a pool of workers, and their answers back (no ROS imports; issue #69): the one
dispatcher of campaigns (the workers under test and each reference stack), suites, re-runs and
baselines.

A `Dispatcher` keeps a queue of keyed requests for one pool. `dispatch` gives each free worker the
first waiting request, skipping one that last failed on that worker (unless the worker is the only
free one); `take` filters a poll's answers: a late answer (for a request given up on that worker,
or already answered) is dropped, an ERROR is queued again at the front up to `max_attempts` runs,
and what is left are final answers, once each. `run_each` runs a list of requests to the end.
"""

from dataclasses import dataclass, field
from typing import Callable, Dict, List, Optional

import numpy as np


@dataclass
class Outcome:
    """What a pool returns for a job: the result as plain values."""

    job: int
    worker: str
    termination: str
    error: str = ""
    sim_time: float = 0.0
    num_control_msgs: int = 0
    trajectory: np.ndarray = field(default_factory=lambda: np.zeros((0, 5), np.float32))  # t, x, y, yaw, yaw rate
    visibility: List[float] = field(default_factory=list)
    removed: List[list] = field(default_factory=list)  # [layout, instance, reason]
    collision_with: str = ""
    wall_time: float = 0.0


class Pool:
    """Workers that run scenario requests (the ROS adapter is ros.pool.WorkerPool)."""

    def free(self) -> List[str]:
        raise NotImplementedError

    def submit(self, worker: str, job: int, request: dict):
        raise NotImplementedError

    def poll(self, timeout: float) -> List[Outcome]:
        raise NotImplementedError


class Dispatcher:
    """Keyed requests to one pool (see the module's text). `on_retry(outcome)` is called for each
    ERROR queued again."""

    def __init__(self, pool: Pool, max_attempts: int = 3, on_retry: Optional[Callable[[Outcome], None]] = None):
        self.pool, self.max_attempts, self.on_retry = pool, max_attempts, on_retry
        self.queue: List[int] = []  # keys waiting for a worker, first served first
        self.requests: Dict[int, dict] = {}
        self.running: Dict[int, str] = {}  # key -> the worker it was given to
        self.attempts: Dict[int, int] = {}  # key -> runs given out so far
        self.avoid: Dict[int, str] = {}  # key -> the worker it last failed on

    def add(self, key: int, request: dict):
        self.requests[key] = request
        self.queue.append(key)

    def discard(self, key: int):
        """Forgets a waiting key (its answer is already known)."""
        if key in self.queue:
            self.queue.remove(key)

    def dispatch(self):
        if not self.queue:
            return
        free = self.pool.free()
        for worker in free:
            pick = next((k for k in self.queue if self.avoid.get(k) != worker or len(free) == 1), None)
            if pick is None:
                continue
            self.queue.remove(pick)
            self.attempts[pick] = self.attempts.get(pick, 0) + 1
            self.running[pick] = worker
            self.pool.submit(worker, pick, self.requests[pick])

    def take(self, outcomes: List[Outcome]) -> List[Outcome]:
        """The final answers among `outcomes` (this pool's), in their order."""
        out = []
        for o in outcomes:
            if self.running.get(o.job) != o.worker:
                continue  # a late answer of a run given up on: never counted twice
            del self.running[o.job]
            if o.termination == "ERROR" and self.attempts.get(o.job, 0) < self.max_attempts:
                self.avoid[o.job] = o.worker
                self.queue.insert(0, o.job)
                if self.on_retry:
                    self.on_retry(o)
                continue
            self.requests.pop(o.job, None)
            out.append(o)
        return out

    @property
    def busy(self) -> bool:
        return bool(self.queue or self.running)


def run_each(
    pool: Pool,
    requests: List[dict],
    on_outcome: Callable[[int, Outcome], None],
    poll: float = 0.2,
    max_attempts: int = 3,
    keys: Optional[List[int]] = None,
):
    """Runs each request once on `pool`, outside any campaign (re-runs, suites, baselines): an ERROR
    is run again on another worker, up to `max_attempts` runs; `on_outcome(k, outcome)` as request k
    (of `keys`, default all) ends, in any order. A late answer of a run given up on is ignored."""
    d = Dispatcher(pool, max_attempts)
    keys = list(range(len(requests))) if keys is None else list(keys)
    for k in keys:
        d.add(k, requests[k])
    done = 0
    while done < len(keys):
        d.dispatch()
        for o in d.take(pool.poll(poll)):
            done += 1
            on_outcome(o.job, o)
