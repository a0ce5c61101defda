"""How a campaign moves (docs/experiments.md): its dynamics over windows, rank and top figures,
and the search comparison figure. No ROS."""

import os
from typing import List

import numpy as np

from asg_agent.records.store import FINDING
from asg_agent.records.scenes import scenario_of
from asg_analysis.campaign_metrics import (
    _differential,
    _perception_collision,
    _perception_finding,
    _ref,
)


def dynamics(campaign: dict, rows, budget: int, window: int = 100) -> List[dict]:
    """Where the search placed obstacles, window by window in job order: proxy >= 3 count, the
    share of obstacle coordinates within 2 m of the landscape's edge (a saturated action), and the
    median distance [m] of the obstacles from the straight start-goal segment."""
    rows = sorted(rows, key=lambda r: r["job"])[:budget]
    if not rows:
        return []
    req = scenario_of(campaign, rows[0])
    size = float(req["structural"]["landscape"]["size"])
    op = req["operational"]
    a, b = np.array([op["start_x"], op["start_y"]]), np.array([op["goal_x"], op["goal_y"]])
    out = []
    for i in range(0, len(rows), window):
        chunk = rows[i : i + window]
        p = np.concatenate([np.asarray(r["positions"], float).reshape(-1, 2) for r in chunk])
        t = np.clip((p - a) @ (b - a) / ((b - a) @ (b - a)), 0.0, 1.0)
        dist = np.linalg.norm(p - (a + t[:, None] * (b - a)), axis=1)
        edge = np.minimum(p, size - p).min(axis=1) < 2.0
        out.append(
            {
                "from": i + 1,
                "to": i + len(chunk),
                "ge3": int(sum((r["proxy"] or 0) >= FINDING for r in chunk)),
                "at_edge": float(edge.mean()),
                "median_to_route_m": float(np.median(dist)),
            }
        )
    return out


def rank_figures(campaign: dict, rows, out_prefix: str, ranks: int = 2) -> List[dict]:
    """The paper's Figures 5-8 for an attributed campaign: its top perception-attributable
    scenarios (perception findings first, then differential ones, then perception collisions,
    each by proxy difference) from above, the flawed stack's path beside the ground-truth
    reference's on the same scene. Writes OUT_PREFIX1.png, OUT_PREFIX2.png, ..."""
    from asg_scenario.report import plot_run
    from asg_agent.scoring.proxy import optimal_path, placed_mask

    def diff(r):
        return r["proxy"] - _ref(r)["proxy"]

    ranked, seen = [], set()
    for pred in (_perception_finding, _differential, _perception_collision):
        for r in sorted(
            (r for r in rows if pred(r) and r["job"] not in seen and _ref(r).get("proxy") is not None),
            key=lambda r: -diff(r),
        ):
            ranked.append(r)
            seen.add(r["job"])
    out = []
    for k, r in enumerate(ranked[:ranks], start=1):
        f = _ref(r)
        req = scenario_of(campaign, r)
        removed = r.get("removed") or []
        opt = optimal_path(req, placed_mask(req, removed))
        kind = (
            "perception finding"
            if _perception_finding(r)
            else ("differential finding" if _differential(r) else "perception collision")
        )
        title = (
            f"{campaign['name']}, rank {k}: {kind} (job {r['job']})\nflawed U-Net: proxy {r['proxy']:.2f} "
            f"(yaw {r['yaw_term']:.2f}, PLR {r['plr']:.3f}), {r['termination']}\nground truth: proxy "
            f"{f['proxy']:.2f} (yaw {f.get('yaw_term') or 0:.2f}, PLR {f.get('plr') or 0:.3f}), {f['termination']}"
        )
        path = f"{out_prefix}{k}.png"
        plot_run(
            path,
            req,
            r["trajectory_xy"],
            title=title,
            optimal=opt.points,
            label="flawed U-Net (under test)",
            removed={(l, i) for l, i, *_ in removed},
            others=[("ground-truth labels (reference)", f.get("trajectory_xy") or [], "tab:green")],
        )
        out.append(
            {
                "rank": k,
                "job": r["job"],
                "kind": kind,
                "proxy": r["proxy"],
                "reference_proxy": f["proxy"],
                "figure": os.path.basename(path),
            }
        )
    return out


def top_figure(campaign: dict, rows, out: str) -> dict:
    from asg_scenario.report import plot_run
    from asg_agent.scoring.proxy import optimal_path, placed_mask

    r = max((x for x in rows if x["proxy"] is not None), key=lambda x: x["proxy"])
    req = scenario_of(campaign, r)
    removed_list = r.get("removed") or []
    opt = optimal_path(req, placed_mask(req, removed_list))
    title = (
        f"{campaign['name']}, rank 1 of {len(rows)} (job {r['job']})\nproxy {r['proxy']:.2f} = 0.1 x vis "
        f"{r['vis']:+.2f} + yaw term {r['yaw_term']:.2f} + PLR {r['plr']:.3f}^2\n{r['termination']} after "
        f"{r['sim_time']:.1f} s, driven {r['path_length']:.1f} m, optimal {r['optimal_length']:.1f} m"
    )
    plot_run(
        out, req, r["trajectory_xy"], title=title, removed={(l, i) for l, i, *_ in removed_list}, optimal=opt.points
    )
    return {"job": r["job"], "proxy": r["proxy"], "figure": os.path.basename(out)}


def comparison_figure(curves, budget: int, threshold: float, out: str):
    """Two panels against scenarios spent: finds with proxy >= 3, and the distinct layouts
    among them (distinct_curve); an arm of several seeds as its mean with the min-max shaded."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11.0, 4.2), sharey=True)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, key, ylabel in (
        (axes[0], "curve", "scenarios with proxy >= 3"),
        (axes[1], "distinct", f"distinct layouts among them ({threshold:g} m)"),
    ):
        for k, (arm, runs) in enumerate(curves.items()):
            c = colours[k % len(colours)]
            full = [r[key] for r in runs if r["scenarios"] >= budget]
            if len(full) > 1:
                a = np.stack(full)
                x = np.arange(1, budget + 1)
                ax.plot(x, a.mean(0), color=c, label=f"{arm} (mean of {len(full)} seeds, min-max shaded)")
                ax.fill_between(x, a.min(0), a.max(0), color=c, alpha=0.2)
            for r in runs if len(full) <= 1 else []:
                ax.plot(np.arange(1, r["scenarios"] + 1), r[key], color=c, label=f"{arm} (seed {r['seed']})")
        ax.set_xlabel("scenarios spent")
        ax.set_ylabel(ylabel)
        ax.set_xlim(0, budget)
        ax.grid(alpha=0.3)
        ax.tick_params(labelleft=True)
    axes[0].legend(fontsize=7)
    fig.suptitle(
        "Exp. 1, flawed U-Net: difficult scenarios found against scenarios spent (left), "
        "and how many of them are distinct layouts (right)",
        fontsize=9,
    )
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)
