"""What the action saturation penalty does, measured on the in-process stand-in (docs/agent.md,
"The action saturation penalty"; scripts/repro/asp_effect.sh runs it):

    python3 -m stand_in.asp_effect [--scenarios 1000] [--seeds 3] [--json OUT] [--out PNG]

TD3-PER with and without the penalty, run against the stand-in simulator (fake_pool: cheap, so
several seeds of 1,000 scenarios take minutes), reporting the fraction of action coordinates at the
edge of their range (|a| >= 0.99, an obstacle within 0.5 % of the landscape's border) per 100
scenarios. It measures the search alone, so it lives with the stand-in, beside the tests.
"""

import argparse
import json
import os
import sys
import tempfile
from typing import List

import numpy as np

from asg_agent.paths import REPO
from asg_agent.records.store import Store


def actions_of(store: Store, campaign: str, size: float) -> np.ndarray:
    """(jobs, 2n) actions in [-1, 1] recovered from the stored requests."""
    out = []
    for r in store.rows(campaign):
        req = json.loads(r["request"])
        xy = [(i["x"], i["y"]) for l in req["structural"]["layouts"] for i in l["instances"]]
        out.append(np.asarray(xy, np.float64).ravel() / size * 2.0 - 1.0)
    return np.asarray(out)


def saturated_fraction(actions: np.ndarray, window: int = 100, edge: float = 0.99) -> List[float]:
    sat = (np.abs(actions) >= edge).mean(axis=1)
    return [float(sat[k : k + window].mean()) for k in range(0, len(sat), window)]


def asp_effect(scenarios: int, seeds: int, experiment: str):
    """{METHOD-sSEED: saturated fraction per 100 scenarios} of td3-per-asp and td3-per."""
    from asg_agent.campaign.loop import Campaign
    from asg_agent.campaign.config import CampaignConfig
    from asg_agent.records.experiment import load_experiment
    from asg_agent.search.methods import make_method
    from stand_in.fake_pool import FakePool

    exp = load_experiment(experiment)
    folder = tempfile.mkdtemp()
    store = Store(os.path.join(folder, "asp.sqlite"))
    curves = {}
    for method in ("td3-per-asp", "td3-per"):
        for seed in range(seeds):
            name = f"{method}-s{seed}"
            c = Campaign(
                CampaignConfig(
                    name=name,
                    experiment=exp,
                    method=make_method(method, exp, seed, budget=scenarios),
                    store=store,
                    pool=FakePool(2, seed=seed),
                    total=scenarios,
                    seed=seed,
                    checkpoint=os.path.join(folder, name + ".ckpt"),
                    slots=4,
                    checkpoint_every=10**9,
                )
            )
            c.start()
            c.run(poll_timeout=0.0)
            curves[name] = saturated_fraction(actions_of(store, name, exp.size))
            print(
                f"{name}: saturated fraction per 100 scenarios " + " ".join(f"{v:.2f}" for v in curves[name]),
                file=sys.stderr,
            )
    return curves


def plot(curves: dict, out: str):
    """The PNG of docs/images/asp_effect.png: each arm's mean over seeds, its range shaded."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 3.2))
    for method, colour in (("td3-per-asp", "tab:blue"), ("td3-per", "tab:red")):
        runs = np.array([v for k, v in curves.items() if k.startswith(method + "-s")])
        x = (np.arange(runs.shape[1]) + 0.5) * 100
        ax.plot(x, runs.mean(0), color=colour, label=f"{method} (mean of {len(runs)} seeds)")
        ax.fill_between(x, runs.min(0), runs.max(0), color=colour, alpha=0.2)
    ax.set_xlabel("scenarios")
    ax.set_ylabel("action coordinates at |a| >= 0.99")
    ax.set_ylim(0, 1)
    ax.legend(fontsize=8)
    ax.set_title("Action saturation with and without ASP (stand-in simulator)", fontsize=9)
    fig.tight_layout()
    fig.savefig(out, dpi=120)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="asp_effect", description=__doc__.split("\n\n")[0])
    p.add_argument("--scenarios", type=int, default=1000)
    p.add_argument("--seeds", type=int, default=3)
    p.add_argument("--experiment", default=os.path.join(REPO, "experiments", "exp1.yaml"))
    p.add_argument("--json", default="")
    p.add_argument("--out", default="", help="PNG of the curves")
    args = p.parse_args(argv)
    curves = asp_effect(args.scenarios, args.seeds, args.experiment)
    if args.json:
        os.makedirs(os.path.dirname(os.path.abspath(args.json)), exist_ok=True)
        with open(args.json, "w") as f:
            json.dump(curves, f, indent=1)
    if args.out:
        plot(curves, args.out)
    summary = {
        m: float(np.mean([v[-1] for k, v in curves.items() if k.startswith(m + "-s")]))
        for m in ("td3-per-asp", "td3-per")
    }
    print(json.dumps({"final_saturated_fraction": summary}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
