"""Blocks of a confirmatory study (protocol v4, issue #78): one machine, run back to back, one seed
of every arm in an order drawn from the block's seed, so that CPU-hours compare within a block.
No ROS.

    python3 -m asg_analysis blocks choose PROTOCOL.yaml EXPORTS_DIR > results/STUDY/pilot_choice.json
    python3 -m asg_analysis blocks PROTOCOL.yaml CHOICE.json BLOCK > results/STUDY/block-BLOCK.txt

BLOCK counts from 0: block k runs every arm's k-th seed. The plan's lines are campaigns.sh's
(NAME  BUDGET train ARGS...), headed by the order's seed and the arms in the order drawn.
"""

import json
import random
import sys
from typing import Dict, List

import yaml

from asg_analysis.protocol import launch_args


def resolve(arm: dict, choice: dict) -> dict:
    """The arm with every "pilot" value replaced by the pilot's choice."""
    return {k: (choice[k] if v == "pilot" else v) for k, v in arm.items()}


def block(protocol: dict, choice: dict, k: int) -> List[dict]:
    """The campaigns of block `k`, in the order drawn from its seed."""
    name, budget = protocol["name"], int(protocol["budget"])
    out = []
    for arm, spec in protocol["arms"].items():
        a = resolve(spec, choice)
        if k >= len(a["seeds"]):
            raise ValueError(f"arm {arm}: block {k} but only {len(a['seeds'])} seeds")
        seed = int(a["seeds"][k])
        keys = ("method", "tabu_m", "band_m", "experiment", "reward")  # what an arm may set
        args = launch_args(
            {k: a.get(k) for k in keys}
            | {"seed": seed, "workers": protocol.get("workers", 3), "attribution": protocol.get("attribution", "three")}
        )
        out.append({"name": f"{name}-{arm}-s{seed}", "arm": arm, "seed": seed, "budget": budget, "args": args})
    order_seed = min(c["seed"] for c in out)
    random.Random(order_seed).shuffle(out)
    return out


def plan_text(cs: List[dict], k: int) -> str:
    head = f"# block {k}: one seed of every arm, in the order random.Random({min(c['seed'] for c in cs)}).shuffle drew: {', '.join(c['arm'] for c in cs)}\n"
    return head + "".join(f"{c['name']}  {c['budget']} train {' '.join(c['args'])}\n" for c in cs)


TIE = 5.0  # [per 1,000] pilot means closer than this are a tie (the protocol's choose rule)


def choose(protocol: dict, folder: str) -> dict:
    """The pilot's choice by protocol v4's rule: the arm with the larger mean distinct flaw
    findings (2 m) per 1,000 over the seeds it ran; within TIE of the best, the larger mean at 5 m,
    then the later-listed wider tabu (the rule names novelty5 over novelty2; among equals, the
    larger tabu_m). Every arm's per-seed figures are kept in the choice."""
    import glob
    import os

    from asg_agent.records.export import read_export
    from asg_analysis.endpoints import campaign

    pilot = protocol["pilot"]
    rows = {}
    for arm, spec in pilot["search"].items():
        paths = sorted(glob.glob(os.path.join(folder, f"{protocol['name']}-pilot-{arm}-s*.jsonl.gz")))
        cs = [campaign(*read_export(p), budget=int(pilot["budget"])) for p in paths]
        if cs:
            rows[arm] = {
                "seeds": [c["seed"] for c in cs],
                "per_1000_2m": [c["per_1000"]["2"] for c in cs],
                "per_1000_5m": [c["per_1000"]["5"] for c in cs],
                "mean_2m": sum(c["per_1000"]["2"] for c in cs) / len(cs),
                "mean_5m": sum(c["per_1000"]["5"] for c in cs) / len(cs),
                "spec": spec,
            }
    if not rows:
        raise ValueError(f"no pilot export of {protocol['name']} in {folder}")
    best = max(r["mean_2m"] for r in rows.values())
    near = [a for a, r in rows.items() if r["mean_2m"] >= best - TIE]
    arm = max(near, key=lambda a: (rows[a]["mean_5m"], float(rows[a]["spec"].get("tabu_m", 0.0))))
    spec = rows[arm]["spec"]
    return {
        "arm": arm,
        "method": spec["method"],
        "tabu_m": float(spec.get("tabu_m", 0.0)),
        "experiment": spec["experiment"],
        "reward": spec["reward"],
        "arms": rows,
    }


def run(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["choose"] and len(argv) == 3:
        try:
            with open(argv[1]) as f:
                print(json.dumps(choose(yaml.safe_load(f), argv[2]), indent=1, sort_keys=True))
        except (OSError, ValueError) as e:
            print(f"blocks: {e}", file=sys.stderr)
            return 2
        return 0
    if len(argv) != 3:
        print(__doc__.split("\n\n")[1], file=sys.stderr)
        return 2
    try:
        with open(argv[0]) as f:
            protocol = yaml.safe_load(f)
        with open(argv[1]) as f:
            choice: Dict = json.load(f)
        print(plan_text(block(protocol, choice, int(argv[2])), int(argv[2])), end="")
    except (OSError, ValueError, KeyError) as e:
        print(f"blocks: {e}", file=sys.stderr)
        return 2
    return 0
