"""`coverage-ts`: a search that spreads its findings over the places where the stack fails
(issue #93; no ROS imports).

What a user gains from a campaign is how many of the ways the stack fails it shows: findings at
places it had not found yet. novelty-ts modelled the reward of a whole layout and avoided the
places found; it found the same easy obstacle in many places nearby. This method models the
obstacle, the natural unit of a finding (a finding names the obstacle it hit), and aims
proposals at the cells no finding covers yet:

- **An obstacle-level model.** Every run gives one row per obstacle: its features (its class x a
  cell along x beside the route, its class x how close its sun shadow comes to the route, and how
  many other obstacles stand on the route before it) and whether the run was a finding that hit
  it (1) or not (0; a finding without contact marks no obstacle). Bayesian linear regression
  (scikit-learn's `BayesianRidge`) of that label on the features, refitted after every result,
  estimates each obstacle's chance of being the one a finding hits. A proposal draws one weight
  vector from the posterior (Thompson sampling), so cells the model is unsure of get their turn.
- **Aimed at what is not covered.** A candidate layout's score is the sum over its obstacles of
  that chance times a novelty weight: 1 for an obstacle standing at least `radius_m` [m] from
  every place of its class this campaign found or aims at in a proposal still in flight, else
  `covered_weight`. The best of `candidates` layouts is proposed; the obstacle that gave it most
  is its aim, held as a provisional place until its result is in, so parallel proposals aim
  elsewhere. Nothing is banned: a layout at known places can still win on a high chance.
- **A portfolio of generators.** Candidates come from one of the campaign's generators (by
  default the first two): `uniform` (fresh layouts over the experiment's action space), `band`
  (fresh layouts with each obstacle, with probability 1/2, along the straight start-goal route
  within the experiment's route_lateral_m [m] of it) and `route` (every obstacle there: the
  proposals of route-random, whose band is route_lateral_m) and `mutate` (a quality-diversity
  archive keyed on the failure's place, as DeepHyperion-CS keys its map: per cell of class x
  along-route x lateral at `radius_m` [m], the first layout whose finding opened it; a parent is
  drawn by its curiosity, a Beta posterior of how often its children opened a cell, and the
  candidates are its children, Gaussian mutations of every coordinate of its action with a step
  drawn per child from `mutate_sigmas` [-] of the action's range). Each generator keeps a Beta
  posterior of how often its proposals became a finding at a new place; each proposal draws from
  them (Thompson sampling) to pick its generator, so the campaign moves to the one that pays on
  its scene. The first `init_random` proposals draw the generator at random among those that need
  no archive and the layout uniformly from it; `mutate` joins the draw once the archive holds a
  layout.
- **Two ways to choose among the candidates** (`selection`). `best` (coverage-ts) proposes the
  candidate of the largest score. `veto` (registered as `coverage-veto`) keeps the generator's own
  distribution and only turns away what would repeat: it takes the candidates in the order drawn
  and proposes the first whose expected chance of a finding at a covered place (the sum of its
  covered obstacles' chances) is no larger than its expected chance of a finding at a new place
  (the sum of the others'); when none is, the one where the second most exceeds the first. With
  nothing covered yet it proposes the generator's first candidate, so it starts as its generator
  does, and it moves away only from layouts whose likely finding is a place already shown.

Learns, does not know: nothing here names a class, a size or a place, or holds a prior about
where a stack fails; every class of the scenario gets the same features and the same generators.
Everything is a function of the seed and the results, applied in job order.
"""

from typing import Dict, List, Optional

import numpy as np

from asg_agent.defaults import DEFAULTS
from asg_agent.records.experiment import ROUTE_SPACES, Experiment
from asg_agent.scoring.atlas import RADIUS_M
from asg_agent.scoring.places import DistinctPlaces
from asg_agent.search.base import SearchMethod
from asg_agent.search.surrogate import LATERAL_EDGES, ObstacleFeatures
from asg_scenario.layout import RouteFrame, mesh_of_instances

#: every generator; a campaign uses `generators` of them
GENERATORS = ("uniform", "band", "route", "mutate")
DEFAULT_GENERATORS = tuple(DEFAULTS["generators"].value.split(","))  # asg_agent/defaults.py
AHEAD_BINS = 4  # other obstacles on the route before this one: 0, 1, 2, 3 or more
MATCH_M = 0.05  # [m] a finding's place is the obstacle of its class standing this close to it
MUTATE_SIGMAS = (0.05, 0.1, 0.2)  # [-] the steps of `mutate`'s children, of the action's range [-1, 1]
SELECTIONS = ("best", "veto")  # how a proposal is chosen among the candidates (the module's text)


class CoverageTS(SearchMethod):
    """The search method (see the module's text); registered as `coverage-ts` in methods.py."""

    name = "coverage-ts"

    def __init__(
        self,
        experiment: Experiment,
        seed: int,
        init_random: int = 30,
        candidates: int = 2000,
        radius_m: float = RADIUS_M,
        covered_weight: float = 0.05,
        along_bins: int = 8,
        generators=DEFAULT_GENERATORS,
        mutate_sigmas=MUTATE_SIGMAS,
        selection: str = "best",
    ):
        if not (init_random >= 1 and candidates >= 1 and along_bins >= 1):
            raise ValueError("coverage-ts: init_random, candidates and along_bins must be >= 1")
        if not radius_m > 0.0:
            raise ValueError(f"coverage-ts: radius_m {radius_m} [m] must be > 0")
        generators = tuple(generators)
        if not generators or any(g not in GENERATORS for g in generators) or len(set(generators)) < len(generators):
            raise ValueError(f"coverage-ts: generators {generators}: some of {', '.join(GENERATORS)}, each once")
        if generators == ("mutate",):
            raise ValueError("coverage-ts: generators mutate needs another generator for its first layouts")
        mutate_sigmas = tuple(float(v) for v in mutate_sigmas)
        if not mutate_sigmas or not all(v > 0.0 for v in mutate_sigmas):
            raise ValueError(f"coverage-ts: mutate_sigmas {mutate_sigmas} [-] must be > 0")
        if not 0.0 <= covered_weight <= 1.0:
            raise ValueError(f"coverage-ts: covered_weight {covered_weight} must be in [0, 1]")
        if selection not in SELECTIONS:
            raise ValueError(f"coverage-ts: selection {selection!r}: one of {', '.join(SELECTIONS)}")
        super().__init__(experiment, seed)
        self.selection = selection
        if selection == "veto":
            self.name = "coverage-veto"
        self.init_random, self.candidates, self.generators = int(init_random), int(candidates), generators
        self.radius, self.covered_weight, self.along_bins = float(radius_m), float(covered_weight), int(along_bins)
        self.feat = ObstacleFeatures(experiment)
        self.route = RouteFrame(experiment.scenario)
        self.meshes = np.array(mesh_of_instances(experiment.scenario))
        self.cls = self.feat.cls
        self.n = experiment.position_dim // 2
        k = len(self.feat.classes)
        self.n_lat = self.feat.n_lat
        self.dim = k * self.n_lat * self.along_bins + k * self.n_lat + AHEAD_BINS
        self.actions: List[np.ndarray] = []  # per observed run: its action
        self.X: List[np.ndarray] = []  # per observed run: (n, dim) obstacle features
        self.Y: List[np.ndarray] = []  # per observed run: (n,) 1 for the obstacle a finding hit
        self.found = DistinctPlaces(self.radius)  # the campaign's findings' places
        self.aims: Dict[int, tuple] = {}  # job -> (class, x, y) aimed at, until its result is in
        self.outcomes: Dict[int, tuple] = {}  # job -> (place, finding), until observed
        self.generator_of: Dict[int, str] = {}
        self.wins = {g: [0, 0] for g in generators}  # generator -> [findings at new places, proposals]
        self.mutate_sigmas = mutate_sigmas
        self.archive: Dict[tuple, dict] = {}  # cell -> {"action", "children", "opened"} (mutate)
        self.parent_of: Dict[int, tuple] = {}  # job -> the archive cell its candidates mutated
        self.model = None

    # -- features ----------------------------------------------------------------------------
    def obstacle_cells(self, xy: np.ndarray) -> np.ndarray:
        """(m, n, 3) the three features that are 1 for each obstacle of m layouts (positions
        (m, n, 2) [m]): its place cell, its shadow cell and its count of obstacles ahead."""
        m, n = xy.shape[:2]
        t, d, lat, shadow = self.feat.bins(xy)
        along = np.clip((t * self.along_bins).astype(int), 0, self.along_bins - 1)
        # on the route: within the first lateral edge; before: smaller t
        on = np.abs(d) < self.feat.edges[1]
        ahead = ((t[:, None, :] < t[:, :, None]) & on[:, None, :]).sum(axis=2)
        ahead = np.minimum(ahead, AHEAD_BINS - 1)
        k = len(self.feat.classes)
        cls = np.broadcast_to(self.cls[None, :], (m, n))
        return np.stack(
            [
                (cls * self.along_bins + along) * self.n_lat + lat,
                k * self.n_lat * self.along_bins + cls * self.n_lat + shadow,
                k * self.n_lat * (self.along_bins + 1) + ahead,
            ],
            axis=2,
        )

    def obstacle_features(self, xy: np.ndarray) -> np.ndarray:
        """(m, n, dim) one-hot features of each obstacle of m layouts (positions (m, n, 2) [m])."""
        cells = self.obstacle_cells(xy)
        f = np.zeros(cells.shape[:2] + (self.dim,))
        np.put_along_axis(f, cells, 1.0, axis=2)
        return f

    # -- generators --------------------------------------------------------------------------
    def _band(self, rng, m: int, share: float = 0.5) -> np.ndarray:
        """m fresh actions with each obstacle, with probability `share`, within route_lateral_m
        [m] of the route (uniform along its usable range); the rest of the action uniform."""
        a = rng.uniform(-1.0, 1.0, (m, self.exp.action_dim))
        near = rng.uniform(size=(m, self.n)) < share
        lo, hi = self.route.t_range
        t = rng.uniform(lo, hi, (m, self.n))
        w = self.exp.route_lateral_m
        d = rng.uniform(-w, w, (m, self.n))
        if self.exp.action_space in ROUTE_SPACES:
            u = (t - lo) / (hi - lo) * 2.0 - 1.0
            v = d / (2.0 * w) if self.exp.action_space == "route-wide" else d / w
            pos = np.stack([u, v], axis=2)
        else:
            pos = self.route.point(t, d) / self.exp.size * 2.0 - 1.0
        p = a[:, : 2 * self.n].reshape(m, self.n, 2)
        p[near] = pos[near]
        a[:, : 2 * self.n] = p.reshape(m, 2 * self.n)
        return np.clip(a, -1.0, 1.0)

    def cell(self, place) -> tuple:
        """The archive's cell of a finding's place (class, x, y [m]): its class and the cells of
        `radius` [m] along and across the route."""
        cls, x, y = place
        v = np.array([x, y], np.float64) - self.route.start
        t = float(v @ self.route.along) / self.route.length
        d = float(v @ self.route.normal)
        return (str(cls), int(np.floor(t / self.radius)), int(np.floor(d / self.radius)))

    def _parent(self, rng) -> tuple:
        """The archive's cell whose layout is mutated: the largest draw of each cell's curiosity,
        Beta(1 + children that opened a cell, 1 + children that did not); cells in sorted order."""
        cells = sorted(self.archive)
        draw = [
            rng.beta(1 + self.archive[c]["opened"], 1 + self.archive[c]["children"] - self.archive[c]["opened"])
            for c in cells
        ]
        return cells[int(np.argmax(draw))]

    def _mutants(self, rng, parent: tuple, m: int) -> np.ndarray:
        a = self.archive[parent]["action"]
        sigma = rng.choice(np.asarray(self.mutate_sigmas), size=(m, 1))
        return np.clip(a[None, :] + sigma * rng.standard_normal((m, a.size)), -1.0, 1.0)

    def _candidates(self, rng, generator: str, m: int, job: int) -> np.ndarray:
        if generator == "mutate":
            parent = self._parent(rng)
            self.parent_of[int(job)] = parent
            return self._mutants(rng, parent, m)
        if generator in ("band", "route"):
            return self._band(rng, m, 0.5 if generator == "band" else 1.0)
        return rng.uniform(-1.0, 1.0, (m, self.exp.action_dim))

    def _available(self) -> tuple:
        return tuple(g for g in self.generators if g != "mutate" or self.archive)

    def _generator(self, rng) -> str:
        gens = self._available()
        draw = [rng.beta(1 + w, 1 + n - w) for w, n in (self.wins[g] for g in gens)]
        return gens[int(np.argmax(draw))]

    def _covered(self, xy: np.ndarray) -> np.ndarray:
        """(m, n) True where an obstacle stands within `radius` of a found or aimed place of its
        class (proposals in flight count as found)."""
        m = xy.shape[0]
        known = DistinctPlaces.from_state(self.found.state_dict())
        for p in self.aims.values():
            known.by_class.setdefault(p[0], []).append((p[1], p[2]))
        out = np.zeros((m, self.n), bool)
        for cls, pts in known.by_class.items():
            cols = np.flatnonzero(self.meshes == cls)
            if len(cols) and pts:
                out[:, cols] = known.near(cls, xy[:, cols].reshape(-1, 2)).reshape(m, len(cols))
        return out

    def _veto(self, chance: np.ndarray, covered: np.ndarray) -> int:
        """The candidate `veto` proposes: the first (in the order drawn) whose chance of a finding
        at a covered place is at most its chance of one at a new place; else the largest margin."""
        at_new = np.where(covered, 0.0, chance).sum(axis=1)
        at_covered = np.where(covered, chance, 0.0).sum(axis=1)
        ok = np.flatnonzero(at_covered <= at_new)
        return int(ok[0]) if len(ok) else int(np.argmax(at_new - at_covered))

    # -- the SearchMethod interface ----------------------------------------------------------
    def _rng(self, *keys):
        return np.random.default_rng([self.seed, 17, *keys])

    def propose(self, job, episode, step, state):
        rng = self._rng(2, job)
        first = tuple(g for g in self.generators if g != "mutate")
        gen = first[int(rng.integers(len(first)))] if job < self.init_random else self._generator(rng)
        self.generator_of[int(job)] = gen
        if job < self.init_random or self.model is None:
            return self._candidates(rng, gen, 1, job)[0].astype(np.float32)
        cand = self._candidates(rng, gen, self.candidates, job)
        xy = self.exp.positions_of(cand)
        cov = self.model.sigma_ + 1e-9 * np.eye(self.dim)
        w = rng.multivariate_normal(self.model.coef_, cov, method="cholesky")
        chance = np.clip(w[self.obstacle_cells(xy)].sum(axis=2) + self.model.intercept_, 0.0, 1.0)
        covered = self._covered(xy)
        value = chance * np.where(covered, self.covered_weight, 1.0)
        best = self._veto(chance, covered) if self.selection == "veto" else int(np.argmax(value.sum(axis=1)))
        i = int(np.argmax(value[best]))
        self.aims[int(job)] = (str(self.meshes[i]), float(xy[best, i, 0]), float(xy[best, i, 1]))
        return cand[best].astype(np.float32)

    def outcome(self, job, place, finding: bool):
        self.outcomes[int(job)] = (tuple(place) if place is not None else None, bool(finding))

    def _hit(self, xy: np.ndarray, place) -> Optional[int]:
        """The obstacle of a layout (n, 2) [m] that a finding's place names (None: no contact)."""
        cls, x, y = place
        d = np.hypot(xy[:, 0] - x, xy[:, 1] - y)
        d[self.meshes != cls] = np.inf
        i = int(np.argmin(d))
        return i if d[i] <= MATCH_M else None

    def observe(self, job, episode, step, state, action, reward, next_state, done) -> Dict:
        place, finding = self.outcomes.pop(int(job), (None, False)) if job is not None else (None, False)
        gen = self.generator_of.pop(int(job), None) if job is not None else None
        parent = self.parent_of.pop(int(job), None) if job is not None else None
        if job is not None:
            self.aims.pop(int(job), None)
        if reward is None:
            return {}
        xy = self.exp.positions_of(np.asarray(action, np.float64)[None])
        y = np.zeros(self.n)
        new = False
        if finding and place is not None:
            i = self._hit(xy[0], place)
            if i is not None:
                y[i] = 1.0
            new = self.found.add(place)
        opened = False
        if finding and place is not None and "mutate" in self.generators:
            c = self.cell(place)
            if c not in self.archive:
                self.archive[c] = {"action": np.asarray(action, np.float64), "children": 0, "opened": 0}
                opened = True
        if parent is not None and parent in self.archive:
            self.archive[parent]["children"] += 1
            self.archive[parent]["opened"] += int(opened)
        if gen is not None:
            self.wins[gen][0] += int(new)
            self.wins[gen][1] += 1
        self.actions.append(np.asarray(action, np.float64))
        self.X.append(self.obstacle_features(xy)[0])
        self.Y.append(y)
        self._fit()
        out = {"coverage_found": len(self.found), "coverage_rows": len(self.Y) * self.n}
        if "mutate" in self.generators:
            out["coverage_cells"] = len(self.archive)
        return out

    def _fit(self):
        from sklearn.linear_model import BayesianRidge

        if len(self.Y) < 2:
            return
        self.model = BayesianRidge(fit_intercept=True).fit(np.concatenate(self.X), np.concatenate(self.Y))

    def config(self):
        return {
            "init_random": self.init_random,
            "candidates": self.candidates,
            "radius_m": self.radius,
            "covered_weight": self.covered_weight,
            "along_bins": self.along_bins,
            "lateral_edges": list(LATERAL_EDGES),
            "generators": list(self.generators),
            "mutate_sigmas": list(self.mutate_sigmas),
            "selection": self.selection,
        }

    def state_dict(self):
        return {
            "actions": [a.tolist() for a in self.actions],
            "Y": [y.tolist() for y in self.Y],
            "found": self.found.state_dict(),
            "aims": {str(k): list(v) for k, v in self.aims.items()},
            "outcomes": {str(k): [list(p) if p else None, f] for k, (p, f) in self.outcomes.items()},
            "generator_of": {str(k): v for k, v in self.generator_of.items()},
            "wins": {k: list(v) for k, v in self.wins.items()},
            "archive": [
                [list(c), v["action"].tolist(), v["children"], v["opened"]] for c, v in sorted(self.archive.items())
            ],
            "parent_of": {str(k): list(v) for k, v in self.parent_of.items()},
        }

    def load_state_dict(self, d):
        self.actions = [np.asarray(a, np.float64) for a in d["actions"]]
        self.X = list(self.obstacle_features(self.exp.positions_of(np.asarray(self.actions)))) if self.actions else []
        self.Y = [np.asarray(y, float) for y in d["Y"]]
        self.found = DistinctPlaces.from_state(d["found"])
        self.aims = {int(k): (str(v[0]), float(v[1]), float(v[2])) for k, v in d["aims"].items()}
        self.outcomes = {int(k): (tuple(p) if p else None, bool(f)) for k, (p, f) in d["outcomes"].items()}
        self.generator_of = {int(k): str(v) for k, v in d["generator_of"].items()}
        self.wins = {k: [int(a), int(b)] for k, (a, b) in d["wins"].items()}
        self.archive = {
            (str(c[0]), int(c[1]), int(c[2])): {
                "action": np.asarray(a, np.float64),
                "children": int(n),
                "opened": int(o),
            }
            for c, a, n, o in d.get("archive", [])
        }
        self.parent_of = {int(k): (str(v[0]), int(v[1]), int(v[2])) for k, v in d.get("parent_of", {}).items()}
        self.model = None
        self._fit()


def chance_summary(method: CoverageTS) -> List[tuple]:
    """The model's largest per-obstacle chances by class and cell (for a report): (class, cell
    along [1..along_bins], lateral bin, chance), largest first; empty before a fit."""
    if method.model is None:
        return []
    w = method.model.coef_
    out = []
    for c, name in enumerate(method.feat.classes):
        for a in range(method.along_bins):
            for la in range(method.n_lat):
                v = w[(c * method.along_bins + a) * method.n_lat + la] + method.model.intercept_
                out.append((name, a + 1, la, float(v)))
    return sorted(out, key=lambda r: -r[3])
