"""`novelty-ts`: surrogate-ts that finds the failure in new places (issue #78; no ROS imports).

Round 6's surrogate-ts found the flaw often and in few places: its parents were the first ten
layouts of largest reward (a stable sort of rewards of 0 or 1), and their children, small moves
of a few early hits, hit the same obstacle in the same place again and again. This method keeps
what surrogate-ts learns and changes what it proposes:

- **The same surrogate.** Bayesian linear regression of the reward on each obstacle's class,
  place along and beside the route and shadow (surrogate.ObstacleFeatures), refitted after every
  result and sampled by Thompson sampling: it learns which attributes go with the failure.
- **Tabu around what was found.** The campaign tells the method each result's place
  (scoring/places.py: the obstacle hit, its class and position, or where a run without contact
  ended) and whether it is a finding of the campaign's reward. A finding whose place is new (at
  least `tabu_m` [m] from every earlier one of its class) joins the archive. A candidate layout
  that puts an obstacle of class c within `tabu_m` of an archived place of class c is not
  proposed while any other candidate is left: that failure, there, is known.
- **Parents refreshed.** Children are mutations of the archive's findings, each drawn with
  weight 1 / (1 + the children it already had), so every distinct finding gets its turn and no
  early few hold the search (before the first finding: the layouts of largest reward, ties
  broken at random). Half of the candidates are uniform, as in surrogate-ts.

Learns, does not know: nothing here names a class, a size or a place, or holds a prior about
where a stack fails; the archive holds only what this campaign found. Everything is a function
of the seed and the results, applied in job order.
"""

from typing import Dict, List

import numpy as np

from asg_agent.scoring.places import PRIMARY_RADIUS_M, DistinctPlaces
from asg_agent.search.surrogate import SurrogateTS
from asg_scenario.layout import mesh_of_instances


class NoveltyTS(SurrogateTS):
    """The search method (see the module's text); registered as `novelty-ts` in methods.py."""

    name = "novelty-ts"

    def __init__(self, experiment, seed: int, tabu_m: float = PRIMARY_RADIUS_M, **surrogate):
        super().__init__(experiment, seed, **surrogate)
        self.tabu = DistinctPlaces(tabu_m)
        self.meshes = np.array(mesh_of_instances(experiment.scenario))
        self.parents: List[int] = []  # index into self.actions of each archived finding
        self.children: List[int] = []  # children proposed so far, per parent
        self.outcomes: Dict[int, tuple] = {}  # job -> (place, finding) until observed

    # -- what the campaign tells the method (base.SearchMethod.outcome) -----------------------
    def outcome(self, job, place, finding: bool):
        self.outcomes[int(job)] = (tuple(place) if place is not None else None, bool(finding))

    def observe(self, job, episode, step, state, action, reward, next_state, done) -> Dict:
        place, finding = self.outcomes.pop(int(job), (None, False)) if job is not None else (None, False)
        out = super().observe(job, episode, step, state, action, reward, next_state, done)
        if reward is not None and finding and place is not None and self.tabu.add(place):
            self.parents.append(len(self.actions) - 1)
            self.children.append(0)
        return dict(out, novelty_archive=len(self.parents)) if out else out

    # -- proposals --------------------------------------------------------------------------
    def _parents(self, rng, k: int) -> np.ndarray:
        """k parent indices: archived findings, each weighted 1 / (1 + its children); before the
        first finding, the layouts of largest reward (ties at random)."""
        if self.parents:
            w = 1.0 / (1.0 + np.asarray(self.children, float))
            pick = rng.choice(len(self.parents), k, p=w / w.sum())
            return np.asarray(self.parents)[pick], pick
        r = np.asarray(self.rewards)
        order = np.lexsort((rng.uniform(size=len(r)), -r))[: self.elites]
        return rng.choice(order, k), None

    def _tabu(self, positions: np.ndarray) -> np.ndarray:
        """Whether each candidate (m, n, 2 [m]) puts an obstacle on an archived place of its class."""
        hit = np.zeros(positions.shape[0], bool)
        for cls in self.tabu.by_class:
            cols = np.flatnonzero(self.meshes == cls)
            if len(cols):
                near = self.tabu.near(cls, positions[:, cols].reshape(-1, 2)).reshape(len(positions), len(cols))
                hit |= near.any(axis=1)
        return hit

    def propose(self, job, episode, step, state):
        rng = self._rng(2, job)
        dim = self.exp.action_dim
        if job < self.init_random or self.model is None:
            return rng.uniform(-1.0, 1.0, dim).astype(np.float32)
        n_elite = int(round(self.candidates * self.elite_share)) if self.rewards else 0
        cand = [rng.uniform(-1.0, 1.0, (self.candidates - n_elite, dim))]
        origin = np.full(self.candidates, -1)  # the parent slot of each candidate, -1: uniform
        if n_elite:
            idx, pick = self._parents(rng, n_elite)
            n = self.exp.position_dim // 2
            move = rng.uniform(size=(n_elite, n)) < self.mutate_share
            move[np.arange(n_elite), rng.integers(0, n, n_elite)] = True
            child = np.asarray(self.actions)[idx].copy()
            child[:, : 2 * n] += (rng.normal(0.0, self.mutate_sigma, (n_elite, n, 2)) * move[..., None]).reshape(
                n_elite, 2 * n
            )
            cand.append(np.clip(child, -1.0, 1.0))
            if pick is not None:
                origin[self.candidates - n_elite :] = pick
        cand = np.concatenate(cand)
        cov = self.model.sigma_ + 1e-9 * np.eye(len(self.model.coef_))
        w = rng.multivariate_normal(self.model.coef_, cov, method="cholesky")
        score = self.features.of_actions(cand) @ w
        banned = self._tabu(self.exp.positions_of(cand))
        if not banned.all():
            score = np.where(banned, -np.inf, score)
        best = int(np.argmax(score))
        if origin[best] >= 0:
            self.children[origin[best]] += 1
        return cand[best].astype(np.float32)

    def config(self):
        return dict(super().config(), tabu_m=self.tabu.radius)

    def state_dict(self):
        return dict(
            super().state_dict(),
            tabu=self.tabu.state_dict(),
            parents=list(self.parents),
            children=list(self.children),
            outcomes={str(k): [list(p) if p else None, f] for k, (p, f) in self.outcomes.items()},
        )

    def load_state_dict(self, d):
        self.tabu = DistinctPlaces.from_state(d["tabu"])
        self.parents, self.children = [int(v) for v in d["parents"]], [int(v) for v in d["children"]]
        self.outcomes = {int(k): (tuple(p) if p else None, bool(f)) for k, (p, f) in d["outcomes"].items()}
        super().load_state_dict(d)
