"""Prioritized experience replay (Schaul et al. 2016), proportional variant (no ROS imports).

A sum tree holds one priority p_i = (|delta_i| + eps)^alpha per transition; sampling draws
transition i with probability P(i) = p_i / sum_k p_k by splitting [0, total) into `batch` equal
strata and drawing one point in each; importance weights w_i = (N P(i))^-beta / max_j w_j correct
the bias (normalised by the largest possible weight, that of the smallest priority), with beta
annealed from beta0 to 1 over `beta_steps` sampled batches (TD3Search sets it to the campaign's
batches, so the correction is complete by its end). New transitions get the largest priority
stored at the time, so each is replayed soon.
"""

from typing import Dict

import numpy as np


class SumTree:
    """Binary tree over `capacity` leaves; every inner node is the sum of its children."""

    def __init__(self, capacity: int):
        if capacity < 1:
            raise ValueError("capacity must be >= 1")
        self.capacity = capacity
        self.size = 1
        while self.size < capacity:
            self.size *= 2
        self.tree = np.zeros(2 * self.size, dtype=np.float64)

    @property
    def total(self) -> float:
        return float(self.tree[1])

    def set(self, index: int, value: float):
        if not 0 <= index < self.capacity:
            raise IndexError(index)
        if not (value >= 0 and np.isfinite(value)):
            raise ValueError(f"priority {value!r}: must be finite and >= 0")
        i = index + self.size
        self.tree[i] = value
        i //= 2
        while i >= 1:
            self.tree[i] = self.tree[2 * i] + self.tree[2 * i + 1]
            i //= 2

    def set_all(self, values: np.ndarray):
        """Every leaf at once (loading a checkpoint), inner sums rebuilt level by level."""
        values = np.asarray(values, dtype=np.float64)
        if len(values) != self.capacity or not np.all(np.isfinite(values)) or np.any(values < 0):
            raise ValueError("set_all: one finite priority >= 0 per leaf")
        self.tree[:] = 0.0
        self.tree[self.size : self.size + self.capacity] = values
        n = self.size
        while n > 1:
            lo = n // 2
            self.tree[lo:n] = self.tree[n : 2 * n : 2] + self.tree[n + 1 : 2 * n : 2]
            n = lo

    def get(self, index: int) -> float:
        return float(self.tree[index + self.size])

    def find(self, mass: float) -> int:
        """Smallest leaf index whose prefix sum exceeds `mass` (0 <= mass < total), and always a
        leaf with a positive priority while the total is positive: an inner sum may differ from
        the sum of its leaves in the last bit, so the walk never enters a subtree whose sum is 0
        and keeps the residual mass inside the subtree it enters (issue #25)."""
        i = 1
        while i < self.size:
            left, right = self.tree[2 * i], self.tree[2 * i + 1]
            if left > 0.0 and (mass < left or right <= 0.0):
                mass = min(mass, float(np.nextafter(left, 0.0)))
                i = 2 * i
            else:
                mass = min(max(mass - left, 0.0), float(np.nextafter(right, 0.0)))
                i = 2 * i + 1
        return min(i - self.size, self.capacity - 1)


class PrioritizedReplay:
    """Ring buffer of (state, action, reward, next_state, not_done) with proportional priorities."""

    def __init__(
        self,
        capacity: int,
        state_dim: int,
        action_dim: int,
        alpha: float = 0.6,
        beta0: float = 0.4,
        beta_steps: int = 10000,
        eps: float = 1e-3,
    ):
        self.capacity, self.alpha, self.beta0, self.beta_steps, self.eps = capacity, alpha, beta0, beta_steps, eps
        self.tree = SumTree(capacity)
        self.state = np.zeros((capacity, state_dim), np.float32)
        self.action = np.zeros((capacity, action_dim), np.float32)
        self.reward = np.zeros((capacity, 1), np.float32)
        self.next_state = np.zeros((capacity, state_dim), np.float32)
        self.not_done = np.zeros((capacity, 1), np.float32)
        self.ptr = 0
        self.count = 0
        self.samples = 0  # batches drawn so far (beta annealing)
        self.max_priority = 1.0  # the largest |delta| + eps ever seen: a statistic, not the level of new entries

    def __len__(self):
        return self.count

    def beta(self) -> float:
        return min(1.0, self.beta0 + (1.0 - self.beta0) * self.samples / max(1, self.beta_steps))

    def add(self, s, a, r, s2, done: bool):
        i = self.ptr
        self.state[i], self.action[i], self.reward[i] = s, a, r
        self.next_state[i], self.not_done[i] = s2, 0.0 if done else 1.0
        # The largest priority stored now (before this slot is overwritten), 1 in an empty buffer.
        stored = self.tree.tree[self.tree.size : self.tree.size + self.count]
        self.tree.set(i, float(stored.max()) if self.count else 1.0)
        self.ptr = (self.ptr + 1) % self.capacity
        self.count = min(self.count + 1, self.capacity)

    def sample(self, batch: int, rng: np.random.Generator) -> Dict[str, np.ndarray]:
        if self.count == 0:
            raise ValueError("sampling from an empty replay buffer")
        total = self.tree.total
        bounds = np.linspace(0.0, total, batch + 1)
        idx = np.array(
            [self.tree.find(min(rng.uniform(bounds[k], bounds[k + 1]), np.nextafter(total, 0))) for k in range(batch)]
        )
        p = np.array([self.tree.get(i) for i in idx]) / total
        beta = self.beta()
        # Normalised by the largest weight any stored transition could get (the smallest priority).
        leaves = self.tree.tree[self.tree.size : self.tree.size + self.count]
        p_min = leaves[leaves > 0].min() / total
        w = (self.count * p) ** (-beta) / (self.count * p_min) ** (-beta)
        self.samples += 1
        return {
            "index": idx,
            "weight": w.astype(np.float32)[:, None],
            "state": self.state[idx],
            "action": self.action[idx],
            "reward": self.reward[idx],
            "next_state": self.next_state[idx],
            "not_done": self.not_done[idx],
        }

    def update_priorities(self, idx, td_errors):
        for i, e in zip(idx, np.abs(np.asarray(td_errors, dtype=np.float64)).ravel()):
            p = float(e) + self.eps
            self.max_priority = max(self.max_priority, p)
            self.tree.set(int(i), p**self.alpha)

    def state_dict(self) -> dict:
        n = self.count
        return {
            "capacity": self.capacity,
            "ptr": self.ptr,
            "count": n,
            "samples": self.samples,
            "beta_steps": self.beta_steps,
            "max_priority": self.max_priority,
            "priorities": self.tree.tree[self.tree.size : self.tree.size + self.capacity].copy(),
            "state": self.state[:n].copy() if n < self.capacity else self.state.copy(),
            "action": self.action[:n].copy() if n < self.capacity else self.action.copy(),
            "reward": self.reward[:n].copy() if n < self.capacity else self.reward.copy(),
            "next_state": self.next_state[:n].copy() if n < self.capacity else self.next_state.copy(),
            "not_done": self.not_done[:n].copy() if n < self.capacity else self.not_done.copy(),
        }

    def load_state_dict(self, d: dict):
        if d["capacity"] != self.capacity:
            raise ValueError(f"replay buffer capacity {d['capacity']} in the checkpoint, {self.capacity} configured")
        n = d["count"]
        for key in ("state", "action", "reward", "next_state", "not_done"):
            getattr(self, key)[: len(d[key])] = d[key]
        self.ptr, self.count, self.samples, self.max_priority = d["ptr"], n, d["samples"], d["max_priority"]
        # A resumed campaign keeps the schedule it began with, whatever budget it resumes with.
        self.beta_steps = d.get("beta_steps", self.beta_steps)
        self.tree.set_all(d["priorities"])
