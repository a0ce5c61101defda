"""Blocks of a confirmatory study (protocol v4, issue #78): one machine, run back to back, one seed
of every arm in an order drawn from the block's seed, so that CPU-hours compare within a block.
No ROS.

    python3 -m asg_analysis.blocks PROTOCOL.yaml CHOICE.json BLOCK > results/STUDY/block-BLOCK.txt

BLOCK counts from 0: block k runs every arm's k-th seed. The plan's lines are campaigns.sh's
(NAME  BUDGET train ARGS...), headed by the order's seed and the arms in the order drawn.
"""

import json
import random
import sys
from typing import Dict, List

import yaml

#: an arm's keys and the train.launch argument each becomes
ARGS = (
    ("method", "method"),
    ("tabu_m", "tabu"),
    ("band_m", "route_band"),
    ("experiment", "experiment"),
    ("reward", "reward"),
)


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
        args = [
            f"{flag}:={a[key]:g}" if isinstance(a.get(key), float) else f"{flag}:={a[key]}"
            for key, flag in ARGS
            if a.get(key) is not None
        ]
        args += [
            f"seed:={seed}",
            f"workers:={protocol.get('workers', 3)}",
            f"attribution:={protocol.get('attribution', 'three')}",
        ]
        out.append({"name": f"{name}-{arm}-s{seed}", "arm": arm, "seed": seed, "budget": budget, "args": args})
    order_seed = min(c["seed"] for c in out)
    random.Random(order_seed).shuffle(out)
    return out


def plan_text(cs: List[dict], k: int) -> str:
    head = f"# block {k}: one seed of every arm, in the order random.Random({min(c['seed'] for c in cs)}).shuffle drew: {', '.join(c['arm'] for c in cs)}\n"
    return head + "".join(f"{c['name']}  {c['budget']} train {' '.join(c['args'])}\n" for c in cs)


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
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


if __name__ == "__main__":
    sys.exit(main())
