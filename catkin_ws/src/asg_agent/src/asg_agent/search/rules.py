"""Rules over a scene's generic attributes, and the sampler that knows only a rule (issue #78; no
ROS imports).

A rule is a conjunction of conditions on the features of a layout that the surrogate searches
use (surrogate.ObstacleFeatures: per class of the scenario, how many of its obstacles stand in
each cell along and beside the straight start-goal route, and how close their shadows come to
it; then the free textural and terrain values of the action). asg_analysis.rules learns rules from
a campaign's results; this module says whether a layout satisfies one and draws fresh layouts
that do.

`rule-sampler` is the check of a rule on fresh samples: uniform layouts of the experiment's
action space (as `random` draws them) kept only where the rule holds, each job's from its own
generator (seed, job). The same sampler without the rule is `random` in the same experiment: the
base rate. Nothing in either names a class, a size or a place beyond what the rule file says.
"""

import json
from dataclasses import dataclass
from typing import Sequence

import math
import re

import numpy as np

from asg_agent.search.base import SearchMethod, _rng
from asg_agent.search.surrogate import ALONG_BINS

#: a surrogate feature's name: "CLASS d<Em qQ", "CLASS d>=Em qQ" or "CLASS shadow d<Em"
_FEATURE = re.compile(r"^(?P<cls>.+?) (?P<shadow>shadow )?d(?P<op><|>=)(?P<edge>[0-9.]+)m(?: q(?P<q>[0-9]+))?$")
_QUARTERS = ("first quarter", "second quarter", "third quarter", "last quarter")[:ALONG_BINS]


def _plural(cls: str) -> str:
    if cls.endswith("y") and cls[-2:-1] not in "aeiou":
        return cls[:-1] + "ies"
    return cls + ("es" if cls.endswith(("s", "x", "ch", "sh")) else "s")


BATCH = 1024  # uniform layouts drawn at a time
MAX_BATCHES = 400  # [-] a rule that holds for none of BATCH x MAX_BATCHES uniform layouts is refused


@dataclass(frozen=True)
class Condition:
    """feature >= threshold (`at_least`) or feature < threshold."""

    feature: str
    at_least: bool
    threshold: float

    def text(self) -> str:
        return f"{self.feature} {'>=' if self.at_least else '<'} {self.threshold:g}"

    def words(self, lower=None) -> str:
        """The condition for a person: `barberry d>=20m q1 >= 1.5` reads "2 or more barberries
        20 m or more from the route in its first quarter" (the features of surrogate.ObstacleFeatures:
        a class, a lateral bin of the distance to the straight start-goal route, a quarter of the
        way along it, or the bin of how close the class's shadows come to the route). `lower` maps a
        bin's upper edge [m] to its lower one (Rule.words gives it)."""
        m = _FEATURE.match(self.feature)
        if not m:
            return self.text()
        cls, shadow, op, edge, q = m.group("cls", "shadow", "op", "edge", "q")
        k = math.ceil(self.threshold)  # counts: >= 1.5 is 2 or more, < 1.5 is at most 1
        if self.at_least:
            count = f"{k} or more {_plural(cls)}" if k > 1 else f"a {cls}"
        else:
            count = f"no {cls}" if k <= 1 else f"at most {k - 1} {_plural(cls) if k > 2 else cls}"
        lo = (lower or {}).get(float(edge)) if op == "<" else None
        if op != "<":
            where = f"{edge} m or more from the route"
        else:
            where = f"between {lo:g} and {edge} m from the route" if lo else f"within {edge} m of the route"
        if shadow:
            return f"{count} whose shadow comes {where}"
        return f"{count} {where} in its {_QUARTERS[int(q) - 1]}"


@dataclass(frozen=True)
class Rule:
    conditions: tuple

    def holds(self, features: np.ndarray, names: Sequence[str]) -> np.ndarray:
        """Whether the rule holds for each row of `features` (m, len(names))."""
        ok = np.ones(features.shape[0], bool)
        for c in self.conditions:
            if c.feature not in names:
                raise ValueError(f"rule: no feature {c.feature!r} in this experiment (e.g. {names[0]!r})")
            v = features[:, list(names).index(c.feature)]
            ok &= (v >= c.threshold) if c.at_least else (v < c.threshold)
        return ok

    def text(self) -> str:
        return " and ".join(c.text() for c in self.conditions) or "(any layout)"

    def words(self, edges=()) -> str:
        """The rule for a person (Condition.words), given the lateral bins' edges [m] (a bin
        "d<E m" then reads "between the edge below E and E m")."""
        lower = {float(b): float(a) for a, b in zip(edges, edges[1:])}
        return "; and ".join(c.words(lower) for c in self.conditions) or "any layout"

    def to_dict(self) -> dict:
        return {"conditions": [[c.feature, ">=" if c.at_least else "<", c.threshold] for c in self.conditions]}

    @classmethod
    def from_dict(cls, d: dict) -> "Rule":
        out = []
        try:
            for feature, op, threshold in d["conditions"]:
                if op not in (">=", "<"):
                    raise ValueError(f"operator {op!r}: >= or <")
                out.append(Condition(str(feature), op == ">=", float(threshold)))
        except (KeyError, TypeError, ValueError) as e:
            raise ValueError(f"rule: {{'conditions': [[feature, '>=' or '<', number], ...]}} expected ({e})") from None
        return cls(tuple(out))


def load_rule(path: str) -> Rule:
    """A rule file: JSON {"conditions": [[feature, ">=" or "<", threshold], ...]} (or a rules file of
    asg_analysis.rules, whose first rule is taken)."""
    try:
        with open(path) as f:
            d = json.load(f)
    except OSError as e:
        raise ValueError(f"rule file {path}: {e.strerror}") from None
    except json.JSONDecodeError as e:
        raise ValueError(f"rule file {path}: not JSON ({e})") from None
    if isinstance(d, dict) and "rules" in d:
        if not d["rules"]:
            raise ValueError(f"rule file {path}: holds no rule")
        d = d["rules"][0]["rule"]
    return Rule.from_dict(d)


class RuleSampler(SearchMethod):
    """Uniform layouts that satisfy `rule` (see the module's text); registered as `rule-sampler`."""

    name = "rule-sampler"

    def __init__(self, experiment, seed, rule: Rule):
        from asg_agent.search.surrogate import ObstacleFeatures

        super().__init__(experiment, seed)
        self.rule = rule
        self.features = ObstacleFeatures(experiment)
        self.names = self.features.names()
        rule.holds(np.zeros((1, self.features.dim)), self.names)  # every feature exists

    def propose(self, job, episode, step, state):
        rng = _rng(self.seed, 12, job)
        for _ in range(MAX_BATCHES):
            a = rng.uniform(-1.0, 1.0, (BATCH, self.exp.action_dim))
            ok = np.flatnonzero(self.rule.holds(self.features.of_actions(a), self.names))
            if len(ok):
                return a[ok[0]].astype(np.float32)
        raise ValueError(f"rule-sampler: {self.rule.text()} holds for none of {BATCH * MAX_BATCHES} uniform layouts")

    def config(self):
        return {"rule": self.rule.to_dict()}
