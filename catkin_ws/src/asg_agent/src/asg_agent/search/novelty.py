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
- **Parents refreshed.** Children come from the archive's findings, each drawn with weight
  1 / (1 + the children it already had), so every distinct finding gets its turn and no early few
  hold the search (before the first finding: the layouts of largest reward, ties broken at random).
- **Operators learnt.** A proposal comes from one of three operators: `uniform` (a fresh layout),
  `mutate` (surrogate-ts's: some obstacles of a parent moved by a Gaussian step) and `shift` (the
  whole parent moved along the straight start-goal route by one Gaussian step, `shift_sigma` of
  the route's length: the same arrangement, somewhere else on the way). Which operator pays is
  learnt: each keeps a Beta posterior of how often its proposals became a new distinct finding,
  and every proposal draws from the posteriors (Thompson sampling) to pick its operator; the
  surrogate then picks the best of that operator's `candidates` (tabu applied).

Learns, does not know: nothing here names a class, a size or a place, or holds a prior about
where a stack fails; the archive holds only what this campaign found. Everything is a function
of the seed and the results, applied in job order.
"""

from typing import Dict, List

import numpy as np

from asg_agent.defaults import DEFAULTS
from asg_agent.scoring.places import DistinctPlaces
from asg_agent.search.surrogate import SurrogateTS
from asg_agent.records.experiment import ROUTE_SPACES
from asg_scenario.layout import RouteFrame, mesh_of_instances

OPERATORS = ("uniform", "mutate", "shift")


class NoveltyTS(SurrogateTS):
    """The search method (see the module's text); registered as `novelty-ts` in methods.py."""

    name = "novelty-ts"

    def __init__(
        self, experiment, seed: int, tabu_m: float = DEFAULTS["tabu_m"].value, shift_sigma: float = 0.1, **surrogate
    ):
        super().__init__(experiment, seed, **surrogate)
        if not shift_sigma > 0.0:
            raise ValueError(f"novelty-ts: shift_sigma {shift_sigma} must be > 0")
        self.tabu = DistinctPlaces(tabu_m)
        self.shift_sigma = float(shift_sigma)
        self.meshes = np.array(mesh_of_instances(experiment.scenario))
        self.parents: List[int] = []  # index into self.actions of each archived finding
        self.children: List[int] = []  # children proposed so far, per parent
        self.outcomes: Dict[int, tuple] = {}  # job -> (place, finding) until observed
        self.operator_of: Dict[int, str] = {}  # job -> the operator that proposed it, until observed
        self.wins = {o: [0, 0] for o in OPERATORS}  # operator -> [new distinct findings, proposals]
        route = RouteFrame(experiment.scenario)
        # one step along the route in action units: u in route spaces, x and y in the absolute one
        if experiment.action_space in ROUTE_SPACES:
            self.along = np.tile([2.0 / (route.t_range[1] - route.t_range[0]), 0.0], experiment.position_dim // 2)
        else:
            self.along = np.tile(route.along / experiment.size * 2.0, experiment.position_dim // 2)

    # -- what the campaign tells the method (base.SearchMethod.outcome) -----------------------
    def outcome(self, job, place, finding: bool):
        self.outcomes[int(job)] = (tuple(place) if place is not None else None, bool(finding))

    def observe(self, job, episode, step, state, action, reward, next_state, done) -> Dict:
        place, finding = self.outcomes.pop(int(job), (None, False)) if job is not None else (None, False)
        op = self.operator_of.pop(int(job), None) if job is not None else None
        out = super().observe(job, episode, step, state, action, reward, next_state, done)
        new = reward is not None and finding and place is not None and self.tabu.add(place)
        if new:
            self.parents.append(len(self.actions) - 1)
            self.children.append(0)
        if op is not None and reward is not None:
            self.wins[op][0] += int(new)
            self.wins[op][1] += 1
        return dict(out, novelty_archive=len(self.parents)) if out else out

    # -- proposals --------------------------------------------------------------------------
    def _parents(self, rng, k: int):
        """k parent indices and their archive slots: archived findings, each weighted 1 / (1 + its
        children); before the first finding, the layouts of largest reward (ties at random)."""
        if self.parents:
            w = 1.0 / (1.0 + np.asarray(self.children, float))
            pick = rng.choice(len(self.parents), k, p=w / w.sum())
            return np.asarray(self.parents)[pick], pick
        r = np.asarray(self.rewards)
        order = np.lexsort((rng.uniform(size=len(r)), -r))[: self.elites]
        return rng.choice(order, k), np.full(k, -1)

    def _tabu(self, positions: np.ndarray) -> np.ndarray:
        """Whether each candidate (m, n, 2 [m]) puts an obstacle on an archived place of its class."""
        hit = np.zeros(positions.shape[0], bool)
        for cls in self.tabu.by_class:
            cols = np.flatnonzero(self.meshes == cls)
            if len(cols):
                near = self.tabu.near(cls, positions[:, cols].reshape(-1, 2)).reshape(len(positions), len(cols))
                hit |= near.any(axis=1)
        return hit

    def _operator(self, rng) -> str:
        """Thompson sampling over the operators' rates of new distinct findings."""
        draw = [rng.beta(1 + w, 1 + n - w) for w, n in (self.wins[o] for o in OPERATORS)]
        return OPERATORS[int(np.argmax(draw))]

    def _candidates(self, rng, op: str):
        """(candidates, archive slot of each one's parent or -1) of one operator."""
        m, dim = self.candidates, self.exp.action_dim
        if op == "uniform":
            return rng.uniform(-1.0, 1.0, (m, dim)), np.full(m, -1)
        idx, slot = self._parents(rng, m)
        child = np.asarray(self.actions)[idx].copy()
        n = self.exp.position_dim // 2
        if op == "mutate":
            move = rng.uniform(size=(m, n)) < self.mutate_share
            move[np.arange(m), rng.integers(0, n, m)] = True
            child[:, : 2 * n] += (rng.normal(0.0, self.mutate_sigma, (m, n, 2)) * move[..., None]).reshape(m, 2 * n)
        else:  # shift: the whole layout along the route
            child[:, : 2 * n] += rng.normal(0.0, self.shift_sigma, (m, 1)) * self.along[None, :]
        return np.clip(child, -1.0, 1.0), slot

    def propose(self, job, episode, step, state):
        rng = self._rng(2, job)
        if job < self.init_random or self.model is None:
            return rng.uniform(-1.0, 1.0, self.exp.action_dim).astype(np.float32)
        op = self._operator(rng)
        cand, slot = self._candidates(rng, op)
        cov = self.model.sigma_ + 1e-9 * np.eye(len(self.model.coef_))
        w = rng.multivariate_normal(self.model.coef_, cov, method="cholesky")
        score = self.features.of_actions(cand) @ w
        banned = self._tabu(self.exp.positions_of(cand))
        if not banned.all():
            score = np.where(banned, -np.inf, score)
        best = int(np.argmax(score))
        if slot[best] >= 0:
            self.children[slot[best]] += 1
        self.operator_of[int(job)] = op
        return cand[best].astype(np.float32)

    def config(self):
        return dict(super().config(), tabu_m=self.tabu.radius, shift_sigma=self.shift_sigma, operators=list(OPERATORS))

    def state_dict(self):
        return dict(
            super().state_dict(),
            found=self.tabu.state_dict(),  # the places found so far (the tabu_m archive)
            parents=list(self.parents),
            children=list(self.children),
            outcomes={str(k): [list(p) if p else None, f] for k, (p, f) in self.outcomes.items()},
            operator_of={str(k): v for k, v in self.operator_of.items()},
            wins={k: list(v) for k, v in self.wins.items()},
        )

    def load_state_dict(self, d):
        self.tabu = DistinctPlaces.from_state(d["found"])
        self.parents, self.children = [int(v) for v in d["parents"]], [int(v) for v in d["children"]]
        self.outcomes = {int(k): (tuple(p) if p else None, bool(f)) for k, (p, f) in d["outcomes"].items()}
        self.operator_of = {int(k): str(v) for k, v in d["operator_of"].items()}
        self.wins = {k: [int(a), int(b)] for k, (a, b) in d["wins"].items()}
        super().load_state_dict(d)
