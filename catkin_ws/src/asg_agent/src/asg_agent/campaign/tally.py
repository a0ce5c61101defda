"""A campaign's running counts (no ROS imports): the stack under test's proxies, errors and
retries, the attribution classes, and the differential figures of a ground-truth reference. A
plain dict, so that a checkpoint keeps it as it is; the campaign loop calls these as scenarios
and their reference runs come in, and `status` is what its progress bar and summary show."""

import math
import time

from asg_agent.scoring import attribution as attr
from asg_agent.scoring.atlas import Coverage
from asg_agent.scoring.places import PRIMARY_RADIUS_M, DistinctPlaces


def new() -> dict:
    """best/ge3/ge4: the proxy of the stack under test; diff_best/diff_ge1: the differential
    reward (proxy - ground-truth proxy), its largest and how often it reached 1; perception/stack:
    findings (proxy >= 3) with the reference below 2 / at least 3; findings/places: the campaign's
    findings (its reward's, rewards.Reward.finding_at) and their distinct places at
    PRIMARY_RADIUS_M (scoring/places.py), counted in job order; coverage: with a failure atlas,
    which of its places the findings cover and the new places beyond it (scoring/atlas.py)."""
    return {
        "best": -math.inf,
        "ge3": 0,
        "ge4": 0,
        "errors": 0,
        "retries": 0,
        "diff_best": -math.inf,
        "diff_ge1": 0,
        "perception": 0,
        "stack": 0,
        "classes": attr.count_classes(()),
        "findings": 0,
        "places": DistinctPlaces(PRIMARY_RADIUS_M).state_dict(),
        "coverage": {"covered": [], "new": []},
    }


def finding(stats: dict, place, atlas=None) -> bool:
    """A finding of the campaign's reward applied, in job order: True when its place is distinct.
    With `atlas` (scoring.atlas.Atlas of the campaign's identity) it also counts what it covers."""
    seen = DistinctPlaces.from_state(stats["places"])
    new = seen.add(place)
    stats["findings"] += 1
    stats["places"] = seen.state_dict()
    if atlas is not None:
        cov = _coverage(stats, atlas)
        cov.add(place)
        stats["coverage"] = cov.state_dict()
    return new


def _coverage(stats: dict, atlas) -> Coverage:
    cov = Coverage(atlas)
    cov.load_state_dict(stats.get("coverage") or {"covered": [], "new": []})
    return cov


def scenario(stats: dict, terms, label, candidate: bool):
    """A scenario stored: its proxy terms (None for an ERROR) and attribution label."""
    if candidate:
        stats["classes"][attr.PENDING] += 1
    elif label is not None:
        stats["classes"][label] += 1
    if terms:
        stats["best"] = max(stats["best"], terms.proxy)
        stats["ge3"] += terms.proxy >= attr.FINDING
        stats["ge4"] += terms.proxy >= attr.FINDING_STRONG
    else:
        stats["errors"] += 1


def attributed(stats: dict, cls: str, proxy, truth_proxy):
    """A candidate's reference runs are in: its class, and (with ground truth) the differential."""
    classes = stats["classes"]
    classes[attr.PENDING] = max(0, classes.get(attr.PENDING, 0) - 1)
    classes[cls] = classes.get(cls, 0) + 1
    if proxy is not None and truth_proxy is not None:
        diff = proxy - truth_proxy
        stats["diff_best"] = max(stats["diff_best"], diff)
        stats["diff_ge1"] += diff >= attr.DIFFERENTIAL
        _, perception, stack = attr.attribute(proxy, truth_proxy)
        stats["perception"] += perception
        stats["stack"] += stack


def from_summary(stats: dict, summary: dict):
    """The counts of a resumed campaign, from its store's summary."""
    stats.update(
        best=summary["max_proxy"] if summary["max_proxy"] is not None else -math.inf,
        ge3=summary["proxy_ge_3"],
        ge4=summary["proxy_ge_4"],
        errors=summary["terminations"].get("ERROR", 0),
        perception=summary["perception_ge3"],
        stack=summary["stack_ge3"],
        diff_ge1=summary["differential_ge1"],
        classes=summary["classes"],
    )


def found(stats: dict, atlas=None) -> dict:
    """The running findings and their distinct places (the progress bar's and TensorBoard's); with
    an atlas, the places of it they cover (`covered`, of `known`) and the new ones beyond it."""
    out = {"findings": stats["findings"], "distinct": len(DistinctPlaces.from_state(stats["places"]))}
    if atlas is not None:
        c = _coverage(stats, atlas).counts()
        out.update(covered=c["covered"], known=c["known"], coverage_new=c["new"])
    return out


def status(stats: dict, stored: int, total: int, new_here: int, elapsed: float, roles, atlas=None) -> dict:
    """What the progress bar and summary show: `new_here` scenarios stored in `elapsed` [s];
    `coverage` (scoring.atlas.Coverage.counts) with an atlas, else None."""
    truth = attr.TRUTH in roles
    return {
        "done": stored,
        "total": total,
        "rate_per_hour": new_here / max(1e-6, elapsed) * 3600,
        **found(stats),
        "distinct_radius_m": stats["places"]["radius"],
        "coverage": _coverage(stats, atlas).counts() if atlas is not None else None,
        "best": stats["best"],
        "ge3": stats["ge3"],
        "ge4": stats["ge4"],
        "errors": stats["errors"],
        "retries": stats["retries"],
        "diff_best": stats["diff_best"] if truth else None,
        "diff_ge1": stats["diff_ge1"] if truth else None,
        "perception": stats["perception"] if truth else None,
        "stack": stats["stack"] if truth else None,
        # attribution classes (candidates re-run, not_candidate, pending) with named references
        "classes": dict(stats["classes"]) if roles else None,
        "roles": list(roles),
    }


class Stages:
    """Wall seconds and calls per stage of the campaign loop (docs/benchmarks.md: `bench`)."""

    NAMES = ("propose", "update", "proxy", "store", "checkpoint", "dispatch", "wait")

    def __init__(self):
        self.seconds = {n: 0.0 for n in self.NAMES}
        self.calls = {n: 0 for n in self.NAMES}

    def add(self, name: str, t0: float):
        self.seconds[name] += time.perf_counter() - t0
        self.calls[name] += 1
