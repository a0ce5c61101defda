"""Search methods behind one small interface, chosen by name (no ROS imports).

Every method sees the campaign as the paper frames it: episodes of `episode_steps` steps, each
step one simulated scenario. A method proposes an action (the x, y of every obstacle in
[-1, 1]) from the current state and observes (state, action, reward, next state, done) once the
scenario has run; the campaign applies results strictly in proposal order, so a method's
decisions (and with them the whole store) depend on the seed alone, not on which worker
finished first.

State = the current layout (2n values in [-1, 1]) + the trajectory of the last run resampled to
N_path points by arc length (2 N_path values, positions scaled to [-1, 1]) + the step's fraction
of the episode. An episode starts from a seeded random layout and the straight start-goal line
(what a run without obstacles drives).

Methods: `td3-per-asp` (the paper's), its ablations `td3-per`, `td3-asp`, `td3`, and the
baselines `random` (uniform layouts), `route-random` (random layouts with the obstacles near the
straight start-goal route), `annealing` (simulated annealing, a prior method the
paper names), `cmaes` (CMA-ES from the `cma` package, the black-box optimiser an engineer
reaches for first) and `map-elites` (quality diversity: MAP-Elites with the `ribs` package's
grid archive and iso+line emitter, over two behaviour descriptors), and `surrogate-ts` (an online
surrogate of the reward with credit per obstacle, sampled by Thompson sampling: surrogate.py), and
`novelty-ts` (the same surrogate proposing away from the places of the failures already found:
novelty.py), `coverage-ts` and `coverage-veto` (an obstacle-level model of which obstacle a
finding hits, aiming at places not yet covered or turning away layouts expected to repeat one:
coverage.py), and `rule-sampler` (uniform layouts that satisfy a learned rule: the check of a rule
on fresh samples; rules.py).

REGISTRY is the one table of them, name -> builder; `make_method` builds from it and METHODS
lists it. The options a campaign hands each method from its arguments are the CLI's
(cli/campaign.py, OPTIONS).
"""

import math
from typing import Callable, Dict, Optional, Tuple

import numpy as np

from asg_agent.defaults import DEFAULTS
from asg_agent.records.experiment import Experiment
from asg_agent.search.base import SearchMethod, _rng
from asg_agent.search.td3 import TD3Agent, TD3Config
from asg_scenario.layout import RouteFrame


class RandomSearch(SearchMethod):
    """Uniform random layouts, one per job, seeded by (seed, job)."""

    name = "random"

    def propose(self, job, episode, step, state):
        return _rng(self.seed, 2, job).uniform(-1.0, 1.0, self.exp.action_dim).astype(np.float32)


class RouteRandom(SearchMethod):
    """Route-biased random layouts (issue #37's cheapest competitor that knows where failures
    are): each obstacle, with probability `share`, lands in a band of half-width `band` [m] around
    the straight start-goal segment (uniform along it, beyond the safety radius around start and
    goal, which removes obstacles there, and uniform across the band), otherwise anywhere; seeded
    by (seed, job) as `random`. The free textural and terrain values are uniform. Stateless."""

    name = "route-random"

    def __init__(self, experiment, seed, band: float = DEFAULTS["route_band"].value, share: float = 1.0):
        super().__init__(experiment, seed)
        if not (band > 0.0 and 0.0 <= share <= 1.0):
            raise ValueError(f"route-random: band {band} [m] must be > 0 and share {share} in [0, 1]")
        if experiment.action_space != "absolute":
            raise ValueError(
                f"route-random: places obstacles itself; the experiment's action_space must be absolute, "
                f"not {experiment.action_space!r}"
            )
        self.band, self.share = float(band), float(share)
        self.route = RouteFrame(experiment.scenario)

    def propose(self, job, episode, step, state):
        rng = _rng(self.seed, 3, job)
        a = rng.uniform(-1.0, 1.0, self.exp.action_dim)
        n = self.exp.position_dim // 2
        size = self.exp.size
        for k in range(n):
            if rng.uniform() < self.share:
                t, d = rng.uniform(*self.route.t_range), rng.uniform(-self.band, self.band)
                xy = self.route.point(t, d)
                a[2 * k : 2 * k + 2] = xy / size * 2.0 - 1.0
        return a.astype(np.float32)

    def config(self):
        return {"band": self.band, "share": self.share}


class Annealing(SearchMethod):
    """Simulated annealing on the layout (maximising the proxy): a Gaussian step from the
    incumbent, Metropolis acceptance at a temperature falling geometrically from t0 to t1 over
    the campaign's budget; the step size falls from sigma0 to sigma1 likewise. Results are
    accepted in job order, so with W jobs in flight proposals use an incumbent W results old."""

    name = "annealing"

    def __init__(
        self,
        experiment,
        seed,
        budget: int = 1000,
        t0: float = 0.5,
        t1: float = 0.01,
        sigma0: float = 0.3,
        sigma1: float = 0.03,
    ):
        super().__init__(experiment, seed)
        self.budget, self.t0, self.t1, self.sigma0, self.sigma1 = budget, t0, t1, sigma0, sigma1
        self.current = _rng(seed, 3).uniform(-1.0, 1.0, experiment.action_dim).astype(np.float32)
        self.current_value = -math.inf
        self.accepted = 0

    def _frac(self, job):
        return min(1.0, job / max(1, self.budget))

    def propose(self, job, episode, step, state):
        f = self._frac(job)
        sigma = self.sigma0 * (self.sigma1 / self.sigma0) ** f
        step_ = _rng(self.seed, 4, job).normal(0.0, sigma, self.exp.action_dim)
        return np.clip(self.current + step_, -1.0, 1.0).astype(np.float32)

    def observe(self, job, episode, step, state, action, reward, next_state, done):
        if reward is None:
            return {}
        temp = self.t0 * (self.t1 / self.t0) ** self._frac(job)
        u = _rng(self.seed, 5, job).uniform()
        if reward >= self.current_value or u < math.exp((reward - self.current_value) / temp):
            self.current, self.current_value = np.asarray(action, np.float32), float(reward)
            self.accepted += 1
        return {"temperature": temp, "incumbent": self.current_value}

    def config(self):
        return {"budget": self.budget, "t0": self.t0, "t1": self.t1, "sigma0": self.sigma0, "sigma1": self.sigma1}

    def state_dict(self):
        return {"current": self.current, "current_value": self.current_value, "accepted": self.accepted}

    def load_state_dict(self, d):
        self.current, self.current_value, self.accepted = d["current"], d["current_value"], d["accepted"]


class TD3Search(SearchMethod):
    """TD3 with or without PER and the saturation penalty (td3.py)."""

    def __init__(self, experiment, seed, per=True, asp=True, config: Optional[TD3Config] = None, budget: int = 1000):
        super().__init__(experiment, seed)
        from dataclasses import replace

        # The method's name says what it is: PER and the penalty on or off, and the scale-free
        # actor objective only with the penalty (it exists so that the penalty's weight means the
        # same at any reward scale); plain "td3" is TD3's own -Q objective (issue #25).
        cfg = replace(config or TD3Config(), per=per, asp=asp, seed=seed, normalize_q=asp)
        if cfg.per and cfg.per_beta_steps < 1:  # anneal beta to 1 over this campaign's batches
            cfg.per_beta_steps = max(1, (budget - cfg.start_steps) * cfg.updates_per_step)
        self.name = "td3" + ("-per" if per else "") + ("-asp" if asp else "")
        self.agent = TD3Agent(self.states.dim, experiment.action_dim, cfg)

    def propose(self, job, episode, step, state):
        return self.agent.act(state)

    def observe(self, job, episode, step, state, action, reward, next_state, done):
        if reward is None:
            return {}
        self.agent.observe(state, action, reward, next_state, done)
        return self.agent.update() or {}

    def config(self):
        from dataclasses import asdict

        return asdict(self.agent.config)

    def state_dict(self):
        return {"agent": self.agent.state_dict()}

    def load_state_dict(self, d):
        self.agent.load_state_dict(d["agent"])


class CMAES(SearchMethod):
    """CMA-ES (Hansen's `cma` package, pinned by scripts/common.sh) on the layout, maximising the
    reward; each scenario is one candidate, the state is ignored (as random search ignores it).
    Candidates are drawn one per job as jobs are proposed (`ask(1)`), and a generation is told
    once `popsize` rewards are in, in job order. With W jobs in flight the first W candidates of
    a generation come from the distribution before the previous generation was told (a delay of
    one generation for them, which `cma` accepts); everything stays a function of the seed.
    Bounds [-1, 1] by `cma`'s boundary transform; an ERROR run is no candidate."""

    name = "cmaes"

    def __init__(self, experiment, seed, sigma0: float = 0.5, popsize: int = 0):
        super().__init__(experiment, seed)
        import cma

        self.sigma0 = sigma0
        x0 = _rng(seed, 6).uniform(-0.8, 0.8, experiment.action_dim)
        opts = {"seed": 1_000_003 + seed, "bounds": [-1.0, 1.0], "verbose": -9}
        if popsize:
            opts["popsize"] = popsize
        self.es = cma.CMAEvolutionStrategy(x0, sigma0, opts)
        self.popsize = int(self.es.popsize)
        self.asked: Dict[int, np.ndarray] = {}  # job -> candidate, until its reward is in
        self.batch_x, self.batch_f = [], []
        self.generations = 0

    def propose(self, job, episode, step, state):
        x = np.asarray(self.es.ask(1)[0], np.float64)
        self.asked[job] = x
        return np.clip(x, -1.0, 1.0).astype(np.float32)

    def observe(self, job, episode, step, state, action, reward, next_state, done):
        x = self.asked.pop(job, None)
        if reward is None or x is None:
            return {}
        self.batch_x.append(x)
        self.batch_f.append(-float(reward))  # cma minimises
        if len(self.batch_x) < self.popsize:
            return {}
        self.es.tell(self.batch_x, self.batch_f)
        self.batch_x, self.batch_f = [], []
        self.generations += 1
        return {
            "cma_sigma": float(self.es.sigma),
            "cma_generation": self.generations,
            "cma_best": -float(self.es.result.fbest),
        }

    def config(self):
        return {"sigma0": self.sigma0, "popsize": self.popsize}

    def state_dict(self):
        import pickle

        return {
            "es": pickle.dumps(self.es),
            "asked": {int(k): v for k, v in self.asked.items()},
            "batch_x": list(self.batch_x),
            "batch_f": list(self.batch_f),
            "generations": self.generations,
        }

    def load_state_dict(self, d):
        import pickle

        self.es = pickle.loads(d["es"])
        self.asked = {int(k): np.asarray(v) for k, v in d["asked"].items()}
        self.batch_x, self.batch_f, self.generations = list(d["batch_x"]), list(d["batch_f"]), d["generations"]


def _segment_distance(points: np.ndarray, a, b) -> np.ndarray:
    """[m] distance of each point (n, 2) to the segment a-b."""
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    ab = b - a
    t = np.clip(((points - a) @ ab) / max(float(ab @ ab), 1e-12), 0.0, 1.0)
    return np.linalg.norm(points - (a + t[:, None] * ab), axis=1)


class MapElites(SearchMethod):
    """MAP-Elites (Mouret and Clune 2015) with the `ribs` package (pinned by scripts/common.sh):
    a grid archive keeps, per cell of two behaviour descriptors, the layout with the largest
    reward; new layouts are iso+line mutations (Vassiliades and Mouret 2018) of elites drawn
    from the archive, after `init_random` uniform random layouts (a tenth of the budget, at
    most 100, by `make_method`). The descriptors, both [m]:

    - `route_obstacles`: how many obstacles stand within `route_band` of the straight start-goal
      segment (0 .. n, one cell each): how much of the layout the route has to deal with;
    - `deviation`: the largest distance of the driven path from that segment, [0, `max_deviation`]
      in `deviation_bins` cells (beyond the range: the last cell): how far the stack swerved.

    One candidate per job (the emitter's `ask` of a one-solution batch), added to the archive and
    told to the emitter when its result is applied, in job order (what ribs' Scheduler.tell does for
    a batch; the Scheduler's strict ask-tell alternation cannot serve jobs in flight): the archive a
    proposal sees depends on the seed alone. An ERROR run is no candidate. The state is ignored (as
    random search and CMA-ES ignore it)."""

    name = "map-elites"

    def __init__(
        self,
        experiment,
        seed,
        init_random: int = 100,
        iso_sigma: float = 0.05,
        line_sigma: float = 0.2,
        route_band: float = 10.0,
        max_deviation: float = 16.0,
        deviation_bins: int = 16,
    ):
        super().__init__(experiment, seed)
        from ribs.archives import GridArchive
        from ribs.emitters import IsoLineEmitter

        self.init_random, self.iso_sigma, self.line_sigma = init_random, iso_sigma, line_sigma
        self.route_band, self.max_deviation, self.deviation_bins = route_band, max_deviation, deviation_bins
        n = experiment.position_dim // 2
        self.archive = GridArchive(
            solution_dim=experiment.action_dim,
            dims=[n + 1, deviation_bins],
            ranges=[(-0.5, n + 0.5), (0.0, max_deviation)],
            seed=2_000_003 + seed,
        )
        self.emitter = IsoLineEmitter(
            self.archive,
            iso_sigma=iso_sigma,
            line_sigma=line_sigma,
            x0=np.zeros(experiment.action_dim),
            bounds=[(-1.0, 1.0)] * experiment.action_dim,
            batch_size=1,
            seed=3_000_017 + seed,
        )
        self.added = 0

    def descriptors(self, action, path_xy) -> np.ndarray:
        """(route_obstacles, deviation) of a layout and the path driven through it."""
        start, goal = self.states.start, self.states.goal
        near = _segment_distance(self.exp.to_positions(action), start, goal) <= self.route_band
        dev = float(np.max(_segment_distance(np.asarray(path_xy, np.float64).reshape(-1, 2), start, goal)))
        return np.array([float(np.sum(near)), min(dev, self.max_deviation - 1e-6)])

    def propose(self, job, episode, step, state):
        if job < self.init_random:
            return _rng(self.seed, 7, job).uniform(-1.0, 1.0, self.exp.action_dim).astype(np.float32)
        return np.clip(self.emitter.ask()[0], -1.0, 1.0).astype(np.float32)

    def observe(self, job, episode, step, state, action, reward, next_state, done):
        if reward is None or next_state is None:
            return {}
        n = self.exp.action_dim
        path = (
            (np.asarray(next_state[n : n + 2 * self.states.n_path], np.float64).reshape(-1, 2) + 1.0)
            * 0.5
            * self.exp.size
        )
        # What pyribs' Scheduler.tell does for a batch, for one result: the archive's add, then the
        # emitter's tell with the add's info, so that an emitter that learns from its results
        # (e.g. an evolution-strategy emitter) learns; IsoLineEmitter's tell does nothing, so the
        # proposals are those of the add alone (issue #80). The Scheduler itself is not used: its
        # ask and tell must alternate, and a campaign asks again while earlier jobs are in flight.
        solution = np.asarray(action, np.float64)[None, :]
        objective = np.array([float(reward)])
        measures = self.descriptors(action, path)[None, :]
        add_info = self.archive.add(solution, objective, measures)
        self.emitter.tell(solution, objective, measures, add_info)
        self.added += 1
        st = self.archive.stats
        return {"qd_cells": int(st.num_elites), "qd_coverage": float(st.coverage), "qd_best": float(st.obj_max)}

    def config(self):
        return {
            "init_random": self.init_random,
            "iso_sigma": self.iso_sigma,
            "line_sigma": self.line_sigma,
            "route_band": self.route_band,
            "max_deviation": self.max_deviation,
            "deviation_bins": self.deviation_bins,
        }

    def state_dict(self):
        import pickle

        return {"archive_emitter": pickle.dumps((self.archive, self.emitter)), "added": self.added}

    def load_state_dict(self, d):
        import pickle

        self.archive, self.emitter = pickle.loads(d["archive_emitter"])
        self.added = d["added"]


def _init(budget: int) -> int:
    """The random proposals a model-based method starts with: a tenth of the budget, 1 to 100."""
    return max(1, min(100, budget // 10))


def _surrogate(e, seed, budget, td3, o):
    from asg_agent.search.surrogate import SurrogateTS

    return SurrogateTS(e, seed, init_random=_init(budget))


def _novelty(e, seed, budget, td3, o):
    from asg_agent.search.novelty import NoveltyTS

    return NoveltyTS(e, seed, init_random=_init(budget), **o)


def _coverage(selection):
    def build(e, seed, budget, td3, o):
        from asg_agent.search.coverage import CoverageTS

        o = dict(o)
        if isinstance(o.get("generators"), str):  # as the campaign gives it: comma-separated
            o["generators"] = tuple(g.strip() for g in o["generators"].split(","))
        return CoverageTS(e, seed, init_random=_init(budget), selection=selection, **o)

    return build


def _rule_sampler(e, seed, budget, td3, o):
    from asg_agent.search.rules import RuleSampler, load_rule

    if not o.get("rule_file"):
        raise ValueError("rule-sampler: needs a rule file (--rule FILE, train.launch rule:=FILE)")
    return RuleSampler(e, seed, load_rule(o["rule_file"]))


def _td3(per: bool, asp: bool):
    return lambda e, seed, budget, td3, o: TD3Search(e, seed, per=per, asp=asp, config=td3, budget=budget)


#: a method's builder: (experiment, seed, budget, td3_config, its options) -> the method
Builder = Callable[..., SearchMethod]

#: every search method, by the name a campaign gives (--method, method:=), in the order listed
REGISTRY: Dict[str, Builder] = {
    "td3-per-asp": _td3(True, True),
    "td3-per": _td3(True, False),
    "td3-asp": _td3(False, True),
    "td3": _td3(False, False),
    "random": lambda e, seed, budget, td3, o: RandomSearch(e, seed),
    "route-random": lambda e, seed, budget, td3, o: RouteRandom(e, seed, **o),
    "annealing": lambda e, seed, budget, td3, o: Annealing(e, seed, budget=budget),
    "cmaes": lambda e, seed, budget, td3, o: CMAES(e, seed),
    "map-elites": lambda e, seed, budget, td3, o: MapElites(e, seed, init_random=_init(budget)),
    "surrogate-ts": _surrogate,
    "novelty-ts": _novelty,
    "coverage-ts": _coverage("best"),
    "coverage-veto": _coverage("veto"),
    "rule-sampler": _rule_sampler,
}
METHODS: Tuple[str, ...] = tuple(REGISTRY)


def make_method(
    name: str,
    experiment: Experiment,
    seed: int,
    budget: int = 1000,
    td3_config: Optional[TD3Config] = None,
    options: Optional[dict] = None,
) -> SearchMethod:
    """The method `name` (REGISTRY); `options`: its own settings (route-random: band [m], share [-];
    novelty-ts: tabu_m [m]; coverage-ts, coverage-veto: generators; rule-sampler: rule_file)."""
    build = REGISTRY.get(name)
    if build is None:
        raise ValueError(f"method {name!r}: one of {', '.join(METHODS)}")
    return build(experiment, seed, budget, td3_config, dict(options or {}))
