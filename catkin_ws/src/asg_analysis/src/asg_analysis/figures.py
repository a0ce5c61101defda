"""Figures over a campaign store: top-down pictures of its scenarios, and what the action
saturation penalty does (no ROS imports).

    python3 -m asg_analysis asp-effect [--scenarios 1000] [--seeds 3] [--out PNG] [--json OUT]
    python3 -m asg_analysis figure STORE CAMPAIGN [--top 1] [--out figures]

The export itself (export, summary, park, unpark, complete) is asg_agent.cli.store.

`asp-effect` measures what the action saturation penalty does: TD3-PER with and without it,
run against the in-process stand-in simulator (fake_pool: cheap, so several seeds of 1,000
scenarios take a minute), reporting the fraction of action coordinates at the edge of their
range (|a| >= 0.99, an obstacle within 0.5 % of the landscape's border) per 100 scenarios.
"""

import argparse
import json
import os
import sys
import tempfile
from typing import List

import numpy as np

from asg_agent.paths import REPO
from asg_agent.records.store import Store, StoreError, unpack_trajectory


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


def top_down(store: Store, campaign: str, job: int, out: str):
    """Top-down summary of one stored scenario, like the paper's Figures 5-8: obstacles by type
    (removed ones dashed), the driven path, the optimal path dashed, start and goal circles, the
    proxy and its terms in the title."""
    from asg_scenario.report import plot_run
    from asg_agent.scoring.proxy import optimal_path, placed_mask

    row = next((r for r in store.rows(campaign, job - 1) if r["job"] == job), None)
    if row is None:
        raise ValueError(f"campaign {campaign!r} has no job {job}")
    req = json.loads(row["request"])
    removed_list = json.loads(row["removed"])
    removed = {(l, i) for l, i, _ in removed_list}
    opt = optimal_path(req, placed_mask(req, removed_list))
    traj = unpack_trajectory(row["trajectory"])
    title = (
        f"{campaign} job {job} (store id {row['id']})\nproxy {row['proxy']:.2f} = 0.1 x vis {row['vis']:+.2f} "
        f"+ yaw term {row['yaw_term']:.2f} + PLR {row['plr']:.3f}^2\n{row['termination']} after "
        f"{row['sim_time']:.1f} s, driven {row['path_length']:.1f} m, optimal {row['optimal_length']:.1f} m"
    )
    others = []
    if row["reference_runs"]:  # three-stack attribution: the references' paths on the same scene
        colours = {"full": "tab:blue", "ground_truth": "tab:green"}
        for role, run in sorted(json.loads(row["reference_runs"]).items()):
            p = "n/a" if run.get("proxy") is None else f"{run['proxy']:.2f}"
            others.append((f"{role}: {run['termination']}, proxy {p}", run["trajectory_xy"], colours.get(role, "0.5")))
        title += f"\nattribution: {row['attribution']}"
    plot_run(
        out,
        req,
        traj[:, 1:3].tolist(),
        title=title,
        removed=removed,
        optimal=opt.points,
        label="under test" if others else "vehicle",
        others=others,
    )


def asp_effect(scenarios: int, seeds: int, experiment: str):
    from asg_agent.campaign.loop import Campaign
    from asg_agent.campaign.config import CampaignConfig
    from asg_agent.records.experiment import load_experiment
    from asg_agent.testing.fake_pool import FakePool
    from asg_agent.search.methods import make_method

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


def main(argv=None):
    p = argparse.ArgumentParser(prog="asg_analysis", description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    a = sub.add_parser("asp-effect", help="saturated-action fraction with and without ASP (stand-in simulator)")
    a.add_argument("--scenarios", type=int, default=1000)
    a.add_argument("--seeds", type=int, default=3)
    a.add_argument("--experiment", default=os.path.join(REPO, "experiments", "exp1.yaml"))
    a.add_argument("--json", default="")
    a.add_argument("--out", default="", help="PNG of the curves")
    fg = sub.add_parser("figure", help="top-down PNG of the top-k scenarios of a campaign")
    fg.add_argument("store")
    fg.add_argument("campaign")
    fg.add_argument("--top", type=int, default=1)
    fg.add_argument("--job", type=int, action="append", default=[], help="this job instead of the top-k (repeatable)")
    fg.add_argument("--out", default="figures", help="folder for CAMPAIGN_jobN.png")
    args = p.parse_args(argv)
    if args.cmd == "figure":
        try:
            store = Store(args.store, create=False)
        except StoreError as e:
            print(f"error: {e}", file=sys.stderr)
            return 2
        os.makedirs(args.out, exist_ok=True)
        jobs = args.job or [r["job"] for r in store.summary(args.campaign, top=args.top)["top"]]
        for job in jobs:
            path = os.path.join(args.out, f"{args.campaign}_job{job}.png")
            try:
                top_down(store, args.campaign, job, path)
            except ValueError as e:
                print(f"error: {e}", file=sys.stderr)
                return 2
            print(path)
        return 0
    return asp_effect_main(args)


def asp_effect_main(args) -> int:
    curves = asp_effect(args.scenarios, args.seeds, args.experiment)
    if args.json:
        os.makedirs(os.path.dirname(os.path.abspath(args.json)), exist_ok=True)
        with open(args.json, "w") as f:
            json.dump(curves, f, indent=1)
    if args.out:
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
        fig.savefig(args.out, dpi=120)
    summary = {
        m: float(np.mean([v[-1] for k, v in curves.items() if k.startswith(m + "-s")]))
        for m in ("td3-per-asp", "td3-per")
    }
    print(json.dumps({"final_saturated_fraction": summary}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
