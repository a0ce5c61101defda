"""A scene's failure atlas: the known places where the stack under test fails, and how much of it
a campaign covers (no ROS imports).

A finding's place is scoring/places.py's: the obstacle the run hit (its class and position [m])
or, without contact, (NO_CONTACT, where the vehicle ended). An atlas pools every finding of one
*identity* (the scene, the stack under test, its references and the kind of finding: `flaw`,
`regression` or `failure`) from many campaigns and groups them, per class, into places at least
`radius` [m] apart:

- **Grouping, order-free.** Per class, the finding with the most other findings within `radius`
  becomes a place (ties: the smallest x, then y); it and every finding within `radius` of it are
  taken; repeat until none is left. The same findings give the same atlas in any order.
- **Completeness.** Chao1 (Chao 1984, as ecologists estimate the species of a survey from its
  singletons and doubletons): the places seen by exactly one finding (f1) and by exactly two (f2)
  estimate the unseen ones, S_chao1 = S_obs + f1^2 / (2 f2) (f2 = 0: S_obs + f1 (f1 - 1) / 2);
  completeness = S_obs / S_chao1. Beside it Chao2, its incidence form, with the campaigns as the
  sampling units (a place found by one campaign, by two): abundance counts assume independent
  draws, and a search that finds one place a hundred times is not that.
- **Coverage.** A campaign covers a place when one of its findings of the same class lies within
  `radius` [m] of it; recall = the places covered / the atlas's places (also per class). A finding
  within `radius` of no place of its class is *new*: its places (grouped as above, in job order)
  are reported beside the recall, and `add` takes them into the next version of the atlas.

Learns nothing and steers nothing: the atlas measures a campaign; no search method reads it.
The file format is `FORMAT` (JSON, sorted keys); `asg_agent.cli.atlas` builds, extends and reads
it.
"""

import json
import math
from typing import Dict, Iterable, List, Optional, Sequence, Tuple

import numpy as np

from asg_agent.scoring.places import Place

FORMAT = "asg-atlas/1"
RADIUS_M = 5.0  # [m] protocol v5's endpoint radius: a place is covered within this of a finding
FINE_RADIUS_M = 2.0  # [m] the atlas's second grouping, reported beside it
#: the kinds of finding an atlas can pool: a class of three-stack attribution, a release pair's
#: regression, or (no reference) the stack's own failed run
KINDS = ("flaw", "regression", "failure")


def is_finding(row: dict, kind: str) -> bool:
    """Whether an export row (records/export.py) is a finding of `kind` (KINDS)."""
    if kind == "failure":
        return row["termination"] not in ("SUCCESS", "ERROR")
    if kind not in KINDS:
        raise ValueError(f"finding kind {kind!r} is not one of {', '.join(KINDS)}")
    return row.get("attribution") == kind


def group(places: Sequence[Place], radius: float, units: Optional[Sequence] = None) -> List[dict]:
    """The places of `places` at `radius` [m] (the module's order-free grouping): a list of
    {"cls", "x", "y", "findings"} sorted by class, then x, then y; with `units` (the sampling unit
    of each finding, e.g. its campaign) each place also counts the units that found it
    ("campaigns")."""
    if not radius > 0.0:
        raise ValueError(f"radius {radius} [m] must be > 0")
    out = []
    for cls in sorted({p[0] for p in places}):
        idx = [i for i, p in enumerate(places) if p[0] == cls]
        xy = np.array([(places[i][1], places[i][2]) for i in idx], float)
        near = ((xy[:, None, :] - xy[None, :, :]) ** 2).sum(axis=2) < radius * radius
        left = np.ones(len(xy), bool)
        while left.any():
            counts = (near & left[None, :]).sum(axis=1)
            counts[~left] = -1
            best = counts.max()
            tied = np.flatnonzero(counts == best)
            c = tied[np.lexsort((xy[tied, 1], xy[tied, 0]))[0]]
            taken = near[c] & left
            place = {"cls": cls, "x": float(xy[c, 0]), "y": float(xy[c, 1]), "findings": int(taken.sum())}
            if units is not None:
                place["campaigns"] = len({units[idx[k]] for k in np.flatnonzero(taken)})
            out.append(place)
            left &= ~taken
    return sorted(out, key=lambda p: (p["cls"], p["x"], p["y"]))


def chao2(incidences: Iterable[int], units: int) -> Dict[str, float]:
    """Chao2, the incidence form (Chao 1987): places found by exactly one of `units` sampling
    units (Q1) and by exactly two (Q2), S_chao2 = S + (m - 1) / m x Q1^2 / (2 Q2) (Q2 = 0:
    (m - 1) / m x Q1 (Q1 - 1) / 2). Fit for pooled campaigns, whose findings are not independent
    draws: a search finds one place a hundred times in one campaign."""
    a = [int(v) for v in incidences if int(v) > 0]
    s, q1, q2 = len(a), sum(v == 1 for v in a), sum(v == 2 for v in a)
    k = (units - 1) / units if units > 0 else 0.0
    est = s + k * (q1 * q1 / (2.0 * q2) if q2 > 0 else q1 * (q1 - 1) / 2.0)
    return {"observed": s, "q1": q1, "q2": q2, "chao2": est, "completeness": s / est if est > 0 else 1.0}


def chao1(abundances: Iterable[int]) -> Dict[str, float]:
    """Chao1 of places seen `abundances` times each: observed, f1, f2, the estimate and the
    completeness (observed / estimate)."""
    a = [int(v) for v in abundances if int(v) > 0]
    s, f1, f2 = len(a), sum(v == 1 for v in a), sum(v == 2 for v in a)
    est = s + (f1 * f1 / (2.0 * f2) if f2 > 0 else f1 * (f1 - 1) / 2.0)
    return {"observed": s, "f1": f1, "f2": f2, "chao1": est, "completeness": s / est if est > 0 else 1.0}


class Atlas:
    """One identity's places at `radius` [m]: `places` a list of {"cls", "x", "y", "findings"}."""

    def __init__(self, places: Sequence[dict], radius: float = RADIUS_M, identity: Optional[dict] = None):
        if not radius > 0.0:
            raise ValueError(f"radius {radius} [m] must be > 0")
        self.radius = float(radius)
        self.identity = dict(identity or {})
        self.places = [dict(p) for p in places]
        self._by_class: Dict[str, Tuple[np.ndarray, np.ndarray]] = {}
        for i, p in enumerate(self.places):
            self._by_class.setdefault(p["cls"], ([], []))
            self._by_class[p["cls"]][0].append(i)
            self._by_class[p["cls"]][1].append((p["x"], p["y"]))
        self._by_class = {c: (np.array(ix), np.array(xy, float)) for c, (ix, xy) in self._by_class.items()}

    def __len__(self) -> int:
        return len(self.places)

    def classes(self) -> List[str]:
        return sorted(self._by_class)

    def size_of(self, cls: str) -> int:
        return len(self._by_class.get(cls, ((), ()))[0])

    def covered_by(self, p: Place) -> List[int]:
        """The indices of the places a finding at `p` covers (same class, within the radius)."""
        cls, x, y = p
        if cls not in self._by_class:
            return []
        ix, xy = self._by_class[cls]
        d2 = ((xy - np.array([x, y], float)) ** 2).sum(axis=1)
        return [int(i) for i in ix[d2 < self.radius * self.radius]]

    def to_json(self) -> dict:
        return {"radius_m": self.radius, "places": self.places}


class Coverage:
    """A campaign's coverage of an atlas, built finding by finding in job order (the campaign's
    tally keeps its state_dict in its checkpoint)."""

    def __init__(self, atlas: Atlas):
        self.atlas = atlas
        self.covered: set = set()
        self.new: List[Tuple[str, float, float]] = []  # findings of no atlas place, each kept once at the radius

    def add(self, p: Place) -> List[int]:
        """Count a finding at `p`: the atlas places it covers first (none: maybe a new place)."""
        hit = self.atlas.covered_by(p)
        if not hit:
            cls, x, y = p
            r2 = self.atlas.radius**2
            if all(c != cls or (x - a) ** 2 + (y - b) ** 2 >= r2 for c, a, b in self.new):
                self.new.append((str(cls), float(x), float(y)))
        first = [i for i in hit if i not in self.covered]
        self.covered.update(hit)
        return first

    def counts(self) -> dict:
        """covered/known overall and per class, and the new places beyond the atlas."""
        per = {c: [0, self.atlas.size_of(c)] for c in self.atlas.classes()}
        for i in self.covered:
            per[self.atlas.places[i]["cls"]][0] += 1
        return {
            "covered": len(self.covered),
            "known": len(self.atlas),
            "by_class": {c: tuple(v) for c, v in per.items()},
            "new": len(self.new),
        }

    def recall(self) -> float:
        return len(self.covered) / len(self.atlas) if len(self.atlas) else math.nan

    def state_dict(self) -> dict:
        return {"covered": sorted(self.covered), "new": [list(p) for p in self.new]}

    def load_state_dict(self, d: dict):
        self.covered = {int(i) for i in d["covered"]}
        self.new = [(str(c), float(x), float(y)) for c, x, y in d["new"]]


def coverage_text(c: dict) -> str:
    """`covered 31 of 87 known failure places (barberry 20/36, juniper 8/32, no contact 3/19), 1 new`."""
    per = ", ".join(f"{k} {a}/{b}" for k, (a, b) in sorted(c["by_class"].items()))
    return f"covered {c['covered']} of {c['known']} known failure places ({per}), {c['new']} new"


# -- the file ------------------------------------------------------------------------------------
def load(path: str, radius: float = RADIUS_M) -> Atlas:
    """The atlas of the file `path` at `radius` [m] (one of the file's groupings)."""
    try:
        with open(path, encoding="utf-8") as f:
            d = json.load(f)
    except (OSError, ValueError) as e:
        raise ValueError(f"atlas {path}: cannot be read ({e})") from None
    if d.get("format") != FORMAT:
        raise ValueError(f"atlas {path}: format {d.get('format')!r} is not {FORMAT!r}")
    for g in d["groupings"]:
        if abs(g["radius_m"] - radius) < 1e-9:
            return Atlas(g["places"], g["radius_m"], d["identity"])
    have = ", ".join(f"{g['radius_m']:g}" for g in d["groupings"])
    raise ValueError(f"atlas {path}: no grouping at {radius:g} m (it has {have} m)")


def same_identity(a: dict, b: dict) -> List[str]:
    """The keys in which two identities differ (empty: the same scene, stack and finding)."""
    return [k for k in sorted(set(a) | set(b)) if a.get(k) != b.get(k)]
