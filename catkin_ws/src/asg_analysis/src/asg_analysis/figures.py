"""Figures over a campaign store: top-down pictures of its scenarios (no ROS imports).

    python3 -m asg_analysis figures STORE CAMPAIGN [--top 1] [--job N ...] [--out figures]

The export itself (export, summary, park, unpark, complete) is asg_agent.cli.store. What the
action saturation penalty does (docs/agent.md) is measured on the in-process stand-in, beside the
tests: scripts/repro/asp_effect.sh.
"""

import argparse
import json
import os
import sys

from asg_agent.records.store import Store, StoreError, unpack_trajectory


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


def run(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python3 -m asg_analysis figures", description=__doc__.split("\n\n")[0])
    p.add_argument("store")
    p.add_argument("campaign")
    p.add_argument("--top", type=int, default=1)
    p.add_argument("--job", type=int, action="append", default=[], help="this job instead of the top-k (repeatable)")
    p.add_argument("--out", default="figures", help="folder for CAMPAIGN_jobN.png")
    args = p.parse_args(argv)
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
