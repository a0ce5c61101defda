"""`surrogate-ts`: an online surrogate of the reward with credit per obstacle, sampled by
Thompson sampling (issue #67; no ROS imports).

A layout is a set of obstacles. Each obstacle is described by what the scene itself says of it:
its class (the scenario's mesh name), where it stands along the straight start-goal route and how
far beside it, and how close its sun shadow comes to the route. The layout's features are the
sum of its obstacles' one-hot descriptions (`ObstacleFeatures`), so a linear model of them gives
each (class, place) its own credit: which obstacles, where, go with a high reward. The free
textural and terrain values of the action are features as they are.

The model is Bayesian linear regression (scikit-learn's `BayesianRidge`, its priors fitted by
evidence maximisation) of the reward on the features, refitted after every result. A proposal
draws one weight vector from the posterior, scores `candidates` layouts with it and proposes the
best (Thompson sampling): layouts the model is unsure of get their turn, those it is sure are poor
do not. The candidates are half uniform over the action space and half mutations of the layouts
of largest reward so far (each obstacle, with probability `mutate_share` and at least one of them,
moved by a Gaussian step of `mutate_sigma`), so the search both explores and refines. The first `init_random`
proposals are uniform.

Learns, does not know: nothing here names a class, a size or a place, or holds a prior about
where a stack fails. The bins are fractions of the experiment's route band (`route_lateral_m`)
and of the route's length, the same for every class; every class of the scenario gets the same
features. Everything is a function of the seed and the results, applied in job order.
"""

import math
from typing import Dict, List, Optional

import numpy as np

from asg_agent.records.experiment import Experiment
from asg_agent.search.base import SearchMethod
from asg_scenario.catalogue import MESHES
from asg_scenario.layout import RouteFrame, mesh_of_instances

#: [-] lateral bin edges as fractions of the route band's half-width (route_lateral_m), the
#: last bin open: on the route, beside it, at the band's edge, beyond it, far away
LATERAL_EDGES = (0.2, 0.4, 0.7, 1.0, 2.0)
#: along-route bins: quarters of the way from start to goal
ALONG_BINS = 4
MIN_SUN_DEG = 5.0  # [deg] the shadow length's floor, as asg_scenario.votes


class ObstacleFeatures:
    """The features of layouts (positions [m], n x 2 each) of one experiment's scenario."""

    def __init__(self, experiment: Experiment):
        self.exp = experiment
        sc = experiment.scenario
        self.route = RouteFrame(sc)
        meshes = mesh_of_instances(sc)
        self.classes = sorted(set(meshes))
        self.cls = np.array([self.classes.index(m) for m in meshes], int)
        scales = np.array([i["scale"] for l in sc["structural"]["layouts"] for i in l["instances"]], float)
        casts = np.array([i["cast_shadow"] for l in sc["structural"]["layouts"] for i in l["instances"]], bool)
        tex = sc["textural"]
        inc = math.radians(max(float(tex["sun_inclination_deg"]), MIN_SUN_DEG))
        yaw = math.radians(float(tex["sun_yaw_deg"]))
        heights = np.array([MESHES[m].height if m in MESHES else 0.0 for m in meshes], float)
        #: [m] each obstacle's shadow, from its foot away from the sun (0 where it casts none)
        self.shadow = (heights * scales / math.tan(inc) * casts)[:, None] * np.array([-math.cos(yaw), -math.sin(yaw)])
        self.edges = np.array(LATERAL_EDGES) * experiment.route_lateral_m
        self.n_lat = len(self.edges) + 1
        self.per_class = self.n_lat * ALONG_BINS + self.n_lat  # place cells + shadow bins
        self.extra = experiment.action_dim - experiment.position_dim

    @property
    def dim(self) -> int:
        return len(self.classes) * self.per_class + self.extra

    def names(self) -> List[str]:
        """A readable name of every feature (for reports of what the model learned)."""
        lat = [f"d<{e:g}m" for e in self.edges] + [f"d>={self.edges[-1]:g}m"]
        out = []
        for c in self.classes:
            out += [f"{c} {la} q{q + 1}" for q in range(ALONG_BINS) for la in lat]
            out += [f"{c} shadow {la}" for la in lat]
        return out + [f"action[{self.exp.position_dim + k}]" for k in range(self.extra)]

    def _route_coords(self, xy):
        rel = xy - self.route.start
        t = (rel @ self.route.along) / max(self.route.length**2, 1e-12)
        d = rel @ self.route.normal
        return t, d

    def of_actions(self, actions: np.ndarray) -> np.ndarray:
        """(m, dim) features of m actions."""
        a = np.asarray(actions, np.float64).reshape(-1, self.exp.action_dim)
        xy = self.exp.positions_of(a)  # (m, n, 2)
        return self.of_positions(xy, a[:, self.exp.position_dim :])

    def bins(self, xy: np.ndarray):
        """(t, d, lat, shadow_bin) of each obstacle of layouts xy (m, n, 2) [m]: its route
        coordinates t [-] and d [m], its lateral bin and its shadow's (0 .. n_lat - 1)."""
        t, d = self._route_coords(xy)
        lat = np.searchsorted(self.edges, np.abs(d), side="right")
        # the shadow's closest approach to the route line: 0 where it crosses it
        _, d_tip = self._route_coords(xy + self.shadow[None])
        crosses = np.sign(d) != np.sign(d_tip)
        d_shadow = np.where(crosses, 0.0, np.minimum(np.abs(d), np.abs(d_tip)))
        return t, d, lat, np.searchsorted(self.edges, d_shadow, side="right")

    def of_positions(self, xy: np.ndarray, extra: Optional[np.ndarray] = None) -> np.ndarray:
        m, n = xy.shape[0], xy.shape[1]
        t, _, lat, shadow_bin = self.bins(xy)
        along = np.clip((t * ALONG_BINS).astype(int), 0, ALONG_BINS - 1)
        base = self.cls[None, :] * self.per_class
        f = np.zeros((m, self.dim))
        rows = np.repeat(np.arange(m), n)
        np.add.at(f, (rows, (base + along * self.n_lat + lat).ravel()), 1.0)
        np.add.at(f, (rows, (base + self.n_lat * ALONG_BINS + shadow_bin).ravel()), 1.0)
        if self.extra:
            f[:, len(self.classes) * self.per_class :] = extra
        return f


class SurrogateTS(SearchMethod):
    """The search method (see the module's text); registered as `surrogate-ts` in methods.py."""

    name = "surrogate-ts"

    def __init__(
        self,
        experiment: Experiment,
        seed: int,
        init_random: int = 30,
        candidates: int = 2000,
        elite_share: float = 0.5,
        elites: int = 10,
        mutate_share: float = 0.3,
        mutate_sigma: float = 0.15,
    ):
        if not (init_random >= 1 and candidates >= 1 and 0.0 <= elite_share <= 1.0 and elites >= 1):
            raise ValueError("surrogate-ts: init_random, candidates, elites >= 1 and elite_share in [0, 1]")
        if not (0.0 < mutate_share <= 1.0 and mutate_sigma > 0.0):
            raise ValueError("surrogate-ts: mutate_share in (0, 1] and mutate_sigma > 0")
        super().__init__(experiment, seed)
        self.features = ObstacleFeatures(experiment)
        self.init_random, self.candidates, self.elite_share, self.elites = init_random, candidates, elite_share, elites
        self.mutate_share, self.mutate_sigma = mutate_share, mutate_sigma
        self.actions: List[np.ndarray] = []
        self.rewards: List[float] = []
        self.model = None

    # -- the SearchMethod interface (methods.SearchMethod) ----------------------------------------
    def _rng(self, *keys):
        return np.random.default_rng([self.seed, 11, *keys])

    def initial_state(self, episode: int) -> np.ndarray:
        a0 = self._rng(1, episode).uniform(-1.0, 1.0, self.exp.action_dim)
        return self.states.build(a0, self.states.straight_line(), 0)

    def propose(self, job, episode, step, state):
        rng = self._rng(2, job)
        dim = self.exp.action_dim
        if job < self.init_random or self.model is None:
            return rng.uniform(-1.0, 1.0, dim).astype(np.float32)
        n_elite = int(round(self.candidates * self.elite_share)) if self.rewards else 0
        cand = [rng.uniform(-1.0, 1.0, (self.candidates - n_elite, dim))]
        if n_elite:
            order = np.argsort(-np.asarray(self.rewards), kind="stable")[: self.elites]
            parents = np.asarray(self.actions)[rng.choice(order, n_elite)]
            n = self.exp.position_dim // 2
            move = rng.uniform(size=(n_elite, n)) < self.mutate_share
            move[np.arange(n_elite), rng.integers(0, n, n_elite)] = True  # every child moves an obstacle
            step_ = rng.normal(0.0, self.mutate_sigma, (n_elite, n, 2)) * move[..., None]
            child = parents.copy()
            child[:, : 2 * n] += step_.reshape(n_elite, 2 * n)
            cand.append(np.clip(child, -1.0, 1.0))
        cand = np.concatenate(cand)
        cov = self.model.sigma_ + 1e-9 * np.eye(len(self.model.coef_))
        w = rng.multivariate_normal(self.model.coef_, cov, method="cholesky")
        score = self.features.of_actions(cand) @ w
        return cand[int(np.argmax(score))].astype(np.float32)

    def observe(self, job, episode, step, state, action, reward, next_state, done) -> Dict:
        if reward is None:
            return {}
        from sklearn.linear_model import BayesianRidge

        self.actions.append(np.asarray(action, np.float64))
        self.rewards.append(float(reward))
        if len(self.rewards) < 2:
            return {}
        self.model = BayesianRidge(fit_intercept=True).fit(
            self.features.of_actions(np.asarray(self.actions)), np.asarray(self.rewards)
        )
        return {"surrogate_noise_sd": float(1.0 / math.sqrt(self.model.alpha_)), "surrogate_n": len(self.rewards)}

    def credit(self, top: int = 10, within: Optional[str] = None) -> List[tuple]:
        """The features of largest posterior mean weight: (name, weight), largest first; `within`
        a class name keeps that class's cells only.

        Credits compare within a block (one class's place cells, or its shadow cells): in every
        layout a block's cells sum to the class's obstacle count, so the results fix only the
        differences inside a block, and the fit puts each block's weights around zero. A cell of
        one class and a cell of another are not compared by their credits.
        """
        if self.model is None:
            return []
        names, w = self.features.names(), self.model.coef_
        keep = [k for k in np.argsort(-w, kind="stable") if within is None or names[k].startswith(within + " ")]
        return [(names[k], float(w[k])) for k in keep[:top]]

    def config(self):
        return {
            "init_random": self.init_random,
            "candidates": self.candidates,
            "elite_share": self.elite_share,
            "elites": self.elites,
            "mutate_share": self.mutate_share,
            "mutate_sigma": self.mutate_sigma,
            "lateral_edges": list(LATERAL_EDGES),
            "along_bins": ALONG_BINS,
        }

    def state_dict(self):
        return {"actions": [a.tolist() for a in self.actions], "rewards": list(self.rewards)}

    def load_state_dict(self, d):
        self.actions = [np.asarray(a, np.float64) for a in d["actions"]]
        self.rewards = [float(r) for r in d["rewards"]]
        self.model = None
        if len(self.rewards) >= 2:  # the same fit the interrupted run had made
            self.observe(None, 0, 0, None, self.actions.pop(), self.rewards.pop(), None, False)
