"""A campaign's findings and their distinct places, from its store (issue #78; no ROS imports):
what the summary, the report and `train.sh`'s last screen lead with.

A finding is a scenario whose reward reached its reward's `finding_at` (scoring/rewards.py: a
`flaw` or `regression` finding, the stack's own failure, or proxy >= 3 for the paper's proxy); its
place and the distinct count are scoring/places.py's, taken in job order.
"""

import json
from typing import Dict, List

from asg_agent.records.store import Store, unpack_trajectory
from asg_agent.scoring import rewards
from asg_agent.scoring.places import PRIMARY_RADIUS_M, REPORTED_RADII_M, distinct_flags


def finding_rule(settings: dict) -> rewards.Reward:
    """The reward a campaign searched with (its settings' `reward`; the paper's proxy when absent)."""
    return rewards.REGISTRY.get(settings.get("reward") or "proxy", rewards.REGISTRY["proxy"])


def findings(store: Store, name: str) -> List[dict]:
    """The campaign's findings in job order: job, place, termination, attribution and reward."""
    from asg_agent.campaign.loop import run_place

    camp = store.campaign(name)
    settings = json.loads(camp["settings"]) if camp and camp["settings"] else {}
    rule = finding_rule(settings)
    out = []
    for r in store.rows(name):
        value = r["reward"] if r["reward"] is not None else r["proxy"]
        if value is None or value < rule.finding_at:
            continue
        request = json.loads(r["request"])
        xy = unpack_trajectory(r["trajectory"])[:, 1:3]
        out.append(
            {
                "job": r["job"],
                "place": run_place(request, dict(r), xy),
                "termination": r["termination"],
                "attribution": r["attribution"],
                "reward": value,
                "proxy": r["proxy"],
            }
        )
    return out


def distinct_summary(found: List[dict]) -> Dict:
    """Counts of `findings`: in all, distinct at each reported radius [m], and the first finding
    of each distinct place at the primary radius (in job order)."""
    places = [f["place"] for f in found]
    flags = distinct_flags(places, PRIMARY_RADIUS_M)
    return {
        "findings": len(found),
        "distinct": {r: sum(distinct_flags(places, r)) for r in REPORTED_RADII_M},
        "primary_radius_m": PRIMARY_RADIUS_M,
        "first_at_each_place": [f for f, new in zip(found, flags) if new],
        "by_class": _by_class(places),
    }


def _by_class(places) -> Dict[str, int]:
    out: Dict[str, int] = {}
    for cls, _, _ in places:
        out[cls] = out.get(cls, 0) + 1
    return dict(sorted(out.items()))
