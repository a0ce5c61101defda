"""The search methods' common ground (no ROS imports): the state a method sees and the
interface every method implements (methods.py's docstring says how a campaign uses them)."""

from typing import Dict, Optional

import numpy as np

from asg_agent.records.experiment import Experiment
from asg_agent.scoring.proxy import resample_path


def _rng(seed: int, *keys: int) -> np.random.Generator:
    return np.random.default_rng([seed, *keys])


class StateBuilder:
    def __init__(self, experiment: Experiment, n_path: int = 250):
        self.exp, self.n_path = experiment, n_path
        op = experiment.scenario["operational"]
        self.start, self.goal = (op["start_x"], op["start_y"]), (op["goal_x"], op["goal_y"])

    @property
    def dim(self) -> int:
        return self.exp.action_dim + 2 * self.n_path + 1

    def straight_line(self) -> np.ndarray:
        return np.array([self.start, self.goal], dtype=np.float64)

    def build(self, action, path_xy, step: int) -> np.ndarray:
        path = resample_path(path_xy, self.n_path) / self.exp.size * 2.0 - 1.0
        return np.concatenate(
            [np.asarray(action, np.float32).ravel(), path.ravel().astype(np.float32), [step / self.exp.episode_steps]]
        ).astype(np.float32)


class SearchMethod:
    name = "base"

    def __init__(self, experiment: Experiment, seed: int):
        self.exp, self.seed = experiment, seed
        self.states = StateBuilder(experiment)

    def initial_state(self, episode: int) -> np.ndarray:
        a0 = _rng(self.seed, 1, episode).uniform(-1.0, 1.0, self.exp.action_dim)
        return self.states.build(a0, self.states.straight_line(), 0)

    def propose(self, job: int, episode: int, step: int, state: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def observe(self, job, episode, step, state, action, reward: Optional[float], next_state, done: bool) -> Dict:
        return {}

    def outcome(self, job: int, place, finding: bool) -> None:
        """Told by the campaign just before `observe` of the same job: the run's place
        (scoring/places.py: the obstacle hit or where the run ended) and whether it is a finding of
        the campaign's reward (rewards.Reward.finding_at). Methods that avoid places already found
        keep it; the rest ignore it."""

    def config(self) -> dict:
        return {}

    def state_dict(self) -> dict:
        return {}

    def load_state_dict(self, d: dict):
        pass
