"""Every table and figure of docs/experiments.md, recomputed from the compact campaign exports
and re-run results under results/ (no simulation, no ROS; well under a minute).

    python3 -m asg_agent.analysis.experiments [--manifest results/experiments.yaml] [--out docs/experiments]

The manifest names which export serves which table (paths relative to the manifest):

    attributed: {budget: 1000, threshold_m: 5.0, arms: {td3-per-asp: [A, B], random: [...], ...}}
                                                         # round 3: searches on the fixed stack, every
                                                         # scenario attributed (scored by ATTRIBUTED_SCORES)
    table2_attributed: {exp1: comparison/A.jsonl.gz, ...}  # round 3's Table 2: an attributed
                                                         # TD3-PER-ASP campaign per experiment
    weather: {exports: [W.jsonl.gz], attributes: [fog_visibility_m, cloud_cover], bins: 4}
                                                         # issue #27: findings by textural attribute
    conditions: {stack: S, layouts: 300, rows: {LABEL: {experiment: E.yaml, stack: S.jsonl,
                 ground_truth: G.jsonl}}}                # issue #27: paired baselines by condition
    table2: {exp1: campaigns/A.jsonl.gz, ...}            # TD3-PER-ASP campaign per experiment
    comparison: {budget: 1000, arms: {td3-per-asp: [A, B, C], random: [...], ...}}
    diversity: {arms: [td3-per-asp, random], top: 100, threshold_m: 5.0, all_thresholds_m: [2, 5, 10]}
    flaw_or_layout_attributed: {file: R.json, campaign: NAME, export: comparison/A.jsonl.gz}
                                                         # round 3: `rerun --select perception`
    differentials: [{export: comparison/D.jsonl.gz, under_test: flawed U-Net, reference: ground truth,
                     figures: diff_gt}]                  # round 3's differential campaigns
    flaw_or_layout: flaw_or_layout.json                  # from `asg_agent.ros.rerun` (optional)
    differential: {export: campaigns/D.jsonl.gz, under_test: flawed U-Net, reference: full U-Net}
                                                         # a --reference-workers campaign (optional)

Writes OUT/tables.md (the tables, quoted in docs/experiments.md), OUT/attributed_{scenarios,hours}.png,
OUT/search_comparison.png,
OUT/top_EXP.png, OUT/differential_{top,curve}.png and OUT/summary.json (every count, read back by the tests).
"""

import argparse
import json
import os
import sys
from typing import Dict, List, Optional

import numpy as np
import yaml

from asg_agent.analysis.export import counts, read_export
from asg_agent.campaign.store import DIFFERENTIAL, FINDING, REFERENCE_CLEAR
from asg_agent.scoring import attribution as attribution_rule

PAPER = {"exp1": (682, 138, 8.31), "exp2": (126, 7, 6.79), "exp3": (477, 82, 6.67), "exp4": (305, 67, 8.00)}
PAPER_SCENARIOS = 5000
REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), *[".."] * 6))


def active_hours(rows) -> float:
    """Wall time of a campaign from its rows' finish times, gaps over 5 minutes (a campaign
    stopped and resumed later) left out; None when the export predates the field."""
    t = sorted(r["finished"] for r in rows if r.get("finished"))
    if len(t) < 2:
        return None
    gaps = np.diff(t)
    return float(gaps[gaps < 300].sum() + np.median(gaps)) / 3600.0


def ge3_curve(rows, budget: int) -> np.ndarray:
    """Count of proxy >= 3 after each scenario, in job order, up to the budget."""
    rows = sorted(rows, key=lambda r: r["job"])[:budget]
    return np.cumsum([(r["proxy"] or 0) >= FINDING for r in rows])


def layout_distance(a, b, meshes) -> float:
    """[m] mean displacement between two layouts with obstacles matched one to one within each
    type (mesh) so that the total displacement is least (Hungarian assignment)."""
    from scipy.optimize import linear_sum_assignment

    a, b = np.asarray(a, float), np.asarray(b, float)
    total = 0.0
    for m in sorted(set(meshes)):
        idx = [i for i, x in enumerate(meshes) if x == m]
        d = np.linalg.norm(a[idx][:, None, :] - b[idx][None, :, :], axis=2)
        r, c = linear_sum_assignment(d)
        total += d[r, c].sum()
    return total / len(meshes)


def layout_distances(a, others, meshes) -> np.ndarray:
    """layout_distance from layout `a` to each layout of `others` (K x N x 2) at once: exact,
    by trying every matching within a type where a type has at most 6 obstacles, by the
    Hungarian assignment per layout otherwise."""
    import itertools

    a, others = np.asarray(a, float), np.asarray(others, float).reshape(-1, len(meshes), 2)
    total = np.zeros(len(others))
    for m in sorted(set(meshes)):
        idx = [i for i, x in enumerate(meshes) if x == m]
        d = np.linalg.norm(others[:, idx][:, :, None, :] - a[idx][None, None, :, :], axis=3)  # K x n(other) x n(a)
        if len(idx) <= 6:
            perms = np.array(list(itertools.permutations(range(len(idx)))))
            total += d[:, np.arange(len(idx))[None, :], perms].sum(axis=2).min(axis=1)
        else:
            from scipy.optimize import linear_sum_assignment

            for k in range(len(others)):
                r, c = linear_sum_assignment(d[k])
                total[k] += d[k][r, c].sum()
    return total / len(meshes)


def _is_new(rows, threshold: float) -> List[bool]:
    """In the given order: whether each row's layout is farther than `threshold` metres
    (layout_distance) from every earlier new one."""
    kept, new = [], []
    for r in rows:
        p = np.asarray(r["positions"], float)
        new.append(not kept or bool(layout_distances(p, kept, r["meshes"]).min() > threshold))
        if new[-1]:
            kept.append(p)
    return new


def distinct(rows, top: Optional[int], threshold: float, min_proxy: float = -np.inf) -> int:
    """Distinct layouts among the `top` highest-proxy rows (all of them when `top` is None) with
    proxy >= `min_proxy`, taken in rank order (_is_new)."""
    ranked = sorted((r for r in rows if r["proxy"] is not None and r["proxy"] >= min_proxy), key=lambda r: -r["proxy"])[
        :top
    ]
    return sum(_is_new(ranked, threshold))


def distinct_curve(rows, budget: int, threshold: float, min_proxy: float = FINDING, pred=None) -> np.ndarray:
    """Count of distinct finds after each scenario, in job order up to the budget: the
    scenarios with proxy >= `min_proxy` (or for which `pred(row)` holds) taken in the order
    found (_is_new)."""
    rows = sorted(rows, key=lambda r: r["job"])[:budget]
    pred = pred or (lambda r: (r["proxy"] or 0) >= min_proxy)
    finds = [r for r in rows if pred(r)]
    new = dict(zip((id(r) for r in finds), _is_new(finds, threshold)))
    return np.cumsum([new.get(id(r), False) for r in rows]).astype(int)


# Round 3's single-reference predicates live with the rule (scoring/attribution.py).
_perception_finding = attribution_rule.perception_finding
_differential = attribution_rule.differential_finding
_perception_collision = attribution_rule.perception_collision


def _ref(r):
    return r.get("reference") or {}


#: The scores of an attributed campaign (issue #25), each counted and counted distinct: (key, label, predicate)
ATTRIBUTED_SCORES = (
    ("perception", f"perception findings (proxy >= {FINDING:g}, reference < {REFERENCE_CLEAR:g})", _perception_finding),
    ("differential", "differential findings (proxy - reference >= 1)", _differential),
    ("collisions", "perception collisions (the reference drove through)", _perception_collision),
)


def elapsed_hours(rows, budget: int) -> np.ndarray:
    """[h] active wall time after each scenario in job order (active_hours' rule: gaps over 5
    minutes, a campaign stopped and resumed, left out); None when the export has no times."""
    rows = sorted(rows, key=lambda r: r["job"])[:budget]
    t = np.array([r.get("finished") or np.nan for r in rows], float)
    if np.isnan(t).any() or len(t) < 2:
        return None
    order = np.maximum.accumulate(t)  # rows finish out of job order; time spent is the latest finish
    gaps = np.diff(order, prepend=order[0])
    med = float(np.median(gaps[1:][gaps[1:] > 0])) if (gaps[1:] > 0).any() else 0.0
    gaps[0] = med  # the first scenario took about what a typical one takes
    return np.cumsum(np.where(gaps < 300, gaps, med)) / 3600.0


def attributed_comparison(load, section: dict, out: str):
    """Round 3's search comparison: per arm and seed, each of ATTRIBUTED_SCORES counted and
    counted distinct (threshold_m, in the order found) against scenarios spent and wall time."""
    budget, thr = int(section.get("budget", 1000)), float(section.get("threshold_m", 5.0))
    runs, summary = {}, {}
    for arm, rels in section["arms"].items():
        runs[arm] = []
        for rel in rels:
            camp, rows = load(rel)
            rows = sorted(rows, key=lambda r: r["job"])[:budget]
            r = {
                "seed": camp["seed"],
                "name": camp["name"],
                "scenarios": len(rows),
                "export": rel,
                "hours": elapsed_hours(rows, budget),
                "max_proxy": max((x["proxy"] for x in rows if x["proxy"] is not None), default=None),
                "max_difference": max(
                    (
                        x["proxy"] - _ref(x)["proxy"]
                        for x in rows
                        if x["proxy"] is not None and _ref(x).get("proxy") is not None
                    ),
                    default=None,
                ),
                "attributed": sum(bool(_ref(x)) for x in rows),
            }
            for key, _, pred in ATTRIBUTED_SCORES:
                r[key] = np.cumsum([pred(x) for x in rows]).astype(int)
                r[key + "_distinct"] = distinct_curve(rows, budget, thr, pred=pred)
            runs[arm].append(r)
    full = lambda rs: [r for r in rs if r["scenarios"] >= budget]  # noqa: E731
    md = [
        "",
        f"### Search comparison on the fixed stack (round 3: Exp. 1, flawed U-Net, bf16, every scenario "
        f"attributed; budget {budget} scenarios per run; distinct at {thr:g} m)",
        "",
        "| method | seed | scenarios | "
        + " | ".join(f"{lab}: count / distinct" for _, lab, _ in ATTRIBUTED_SCORES)
        + " | largest proxy | largest difference | wall time | scenarios per hour |",
        "|---|---|---|" + "---|" * len(ATTRIBUTED_SCORES) + "---|---|---|---|",
    ]
    for arm, rs in runs.items():
        summary[arm] = []
        for r in rs:
            h = float(r["hours"][-1]) if r["hours"] is not None else None
            summary[arm].append(
                {
                    "seed": r["seed"],
                    "name": r["name"],
                    "export": r["export"],
                    "scenarios": r["scenarios"],
                    "attributed": r["attributed"],
                    "hours": h,
                    "max_proxy": r["max_proxy"],
                    "max_difference": r["max_difference"],
                    **{k: int(r[k][-1]) for k, _, _ in ATTRIBUTED_SCORES},
                    **{k + "_distinct": int(r[k + "_distinct"][-1]) for k, _, _ in ATTRIBUTED_SCORES},
                }
            )
            md.append(
                f"| {arm} | {r['seed']} | {r['scenarios']}"
                + ("" if r["scenarios"] >= budget else " (running)")
                + " | "
                + " | ".join(f"{int(r[k][-1])} / {int(r[k + '_distinct'][-1])}" for k, _, _ in ATTRIBUTED_SCORES)
                + f" | {fmt(r['max_proxy'])} | {fmt(r['max_difference'], '+.2f')} | "
                + (f"{h * 60:.0f} min | {r['scenarios'] / h:,.0f}" if h else "- | -")
                + " |"
            )
    rnd = full(runs.get("random", []))
    if len(runs) > 1 and rnd:
        md += [
            "",
            "Mean over the seeds that reached the budget (min-max), and the ratio to random search's mean:",
            "",
            "| method | seeds | " + " | ".join(f"{lab}, distinct" for _, lab, _ in ATTRIBUTED_SCORES) + " |",
            "|---|---|" + "---|" * len(ATTRIBUTED_SCORES),
        ]
        for arm, rs in runs.items():
            rs = full(rs)
            if not rs:
                continue
            cells = []
            for k, _, _ in ATTRIBUTED_SCORES:
                v = [int(r[k + "_distinct"][-1]) for r in rs]
                base = np.mean([int(r[k + "_distinct"][-1]) for r in rnd])
                cells.append(
                    f"{np.mean(v):.1f} ({min(v)}-{max(v)})" + (f", {np.mean(v) / base:.2f}x" if base > 0 else "")
                )
            md.append(f"| {arm} | {len(rs)} | " + " | ".join(cells) + " |")
    for measure, xlabel in (("scenarios", "scenarios spent"), ("hours", "wall time [h]")):
        attributed_figure(runs, budget, thr, measure, xlabel, os.path.join(out, f"attributed_{measure}.png"))
    # The first arm's first run: its top two perception-attributable scenarios, as Figures 5-8.
    first = next(iter(section["arms"].values()))[0]
    camp, rows = load(first)
    summary["_ranks"] = rank_figures(
        camp, sorted(rows, key=lambda r: r["job"])[:budget], os.path.join(out, "attributed_rank")
    )
    return summary, md


def attributed_figure(runs, budget, thr, measure, xlabel, out):
    """One panel per score, distinct finds against `measure` (scenarios or hours); an arm of
    several seeds as its mean over the budget with the min-max shaded (against hours: each seed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(ATTRIBUTED_SCORES), figsize=(5.0 * len(ATTRIBUTED_SCORES), 4.0))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, (key, label, _) in zip(axes, ATTRIBUTED_SCORES):
        for k, (arm, rs) in enumerate(runs.items()):
            c = colours[k % len(colours)]
            done = [r for r in rs if r["scenarios"] >= budget]
            if measure == "scenarios" and len(done) > 1:
                a = np.stack([r[key + "_distinct"] for r in done])
                x = np.arange(1, budget + 1)
                ax.plot(x, a.mean(0), color=c, label=f"{arm} (mean of {len(done)} seeds, min-max)")
                ax.fill_between(x, a.min(0), a.max(0), color=c, alpha=0.2)
                continue
            for j, r in enumerate(rs):
                x = np.arange(1, r["scenarios"] + 1) if measure == "scenarios" else r["hours"]
                if x is None:
                    continue
                ax.plot(
                    x,
                    r[key + "_distinct"],
                    color=c,
                    lw=1.2,
                    ls=("-", "--", ":")[j % 3],
                    label=f"{arm} (seed {r['seed']})",
                )
        ax.set_xlabel(xlabel)
        ax.set_ylabel(f"distinct ({thr:g} m)")
        ax.set_title(label, fontsize=9)
        ax.set_ylim(bottom=0, top=max(1.0, ax.get_ylim()[1]))
        ax.yaxis.get_major_locator().set_params(integer=True)
        ax.grid(alpha=0.3)
        if measure == "scenarios":
            ax.set_xlim(0, budget)
    axes[0].legend(fontsize=7)
    fig.suptitle(
        f"Exp. 1, flawed U-Net (bf16), every scenario attributed: distinct perception-attributable finds "
        f"against {xlabel}",
        fontsize=10,
    )
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    plt.close(fig)


def _segment_distance_xy(px, py, ax, ay, bx, by) -> float:
    dx, dy = bx - ax, by - ay
    t = 0.0 if dx == dy == 0 else max(0.0, min(1.0, ((px - ax) * dx + (py - ay) * dy) / (dx * dx + dy * dy)))
    return float(np.hypot(px - ax - t * dx, py - ay - t * dy))


#: Issue #27: scene attributes of the terrain, from an export row's `terrain` (flat: absent)
TERRAIN_ATTRIBUTES = {
    "amplitude_m": lambda t, row: float(t.get("amplitude_m", 0.0)),
    "highest_hill_m": lambda t, row: max([h["height_m"] for h in t.get("hills", [])] or [0.0]),
    "deepest_ditch_m": lambda t, row: max([-h["height_m"] for h in t.get("hills", [])] or [0.0]),
    # [m] the nearest hill or ditch of at least 1 m to the straight start-goal line, from its rim
    "hill_from_route_m": lambda t, row: min(
        [
            _segment_distance_xy(h["x"], h["y"], *row["_route"]) - h["radius_m"]
            for h in t.get("hills", [])
            if abs(h["height_m"]) >= 1.0
        ]
        or [np.inf]
    ),
}


def attribute_value(row: dict, attr: str, route=(20.0, 20.0, 80.0, 80.0)) -> float:
    """A scene attribute of an export row: a textural one by name, or `terrain.NAME` of
    TERRAIN_ATTRIBUTES (route: start x, y and goal x, y of the experiment)."""
    if attr.startswith("terrain."):
        return TERRAIN_ATTRIBUTES[attr[len("terrain.") :]](row.get("terrain") or {}, dict(row, _route=route))
    return float(row["textural"][attr])


def obstacles_hit(rows) -> Dict[str, dict]:
    """Collisions of the stack under test by the mesh of the obstacle hit (the export's
    `collision_with`, an index into `meshes`); {} for exports made before it was exported."""
    out: Dict[str, dict] = {}
    for r in rows:
        if r["termination"] != "COLLISION" or r.get("collision_with") is None:
            continue
        c = out.setdefault(r["meshes"][r["collision_with"]], {"collisions": 0, "perception_collisions": 0})
        c["collisions"] += 1
        c["perception_collisions"] += int(_perception_collision(r))
    return dict(sorted(out.items(), key=lambda kv: -kv[1]["collisions"]))


def weather_tables(load, section: dict, out: str, what: str = "weather", figure: str = "weather.png"):
    """Issue #27: attributed campaigns whose experiment frees textural (or terrain) attributes,
    their scenarios binned by each attribute (equal-width bins over the values searched; textural
    names, or terrain.NAME of TERRAIN_ATTRIBUTES): scenarios, ATTRIBUTED_SCORES, collisions of
    the reference stack, and the median proxy of both stacks; and a figure of the proxy
    difference against each attribute."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    attrs, nbins = list(section.get("attributes") or []), int(section.get("bins", 4))
    summary, md = {}, []
    rows = []
    for rel in section["exports"]:
        camp, rs = load(rel)
        rows += [r for r in rs if r.get("textural") and r["proxy"] is not None]
    if not rows or not attrs:
        return summary, md
    route = tuple(section.get("route", (20.0, 20.0, 80.0, 80.0)))
    md += ["", f"### Findings by {what} (issue #27: {', '.join(section['exports'])}, {len(rows)} scenarios)", ""]
    fig, axes = plt.subplots(1, len(attrs), figsize=(5.0 * len(attrs), 3.8), squeeze=False)
    for ax, attr in zip(axes[0], attrs):
        v = np.array([attribute_value(r, attr, route) for r in rows], float)
        finite = v[np.isfinite(v)]
        v = np.where(np.isfinite(v), v, finite.max() if len(finite) else 0.0)  # no hill: the far end
        edges = np.linspace(v.min(), v.max(), nbins + 1)
        idx = np.clip(np.digitize(v, edges[1:-1]), 0, nbins - 1)
        md += [
            f"| {attr} | scenarios | "
            + " | ".join(lab for _, lab, _ in ATTRIBUTED_SCORES)
            + " | reference collisions | median proxy: under test / reference |",
            "|---|---|" + "---|" * (len(ATTRIBUTED_SCORES) + 2),
        ]
        summary[attr] = []
        for b in range(nbins):
            sel = [r for r, k in zip(rows, idx) if k == b]
            cell = {
                "from": float(edges[b]),
                "to": float(edges[b + 1]),
                "scenarios": len(sel),
                **{key: int(sum(pred(r) for r in sel)) for key, _, pred in ATTRIBUTED_SCORES},
                "reference_collisions": int(sum(_ref(r).get("termination") == "COLLISION" for r in sel)),
            }
            refs = [_ref(r)["proxy"] for r in sel if _ref(r).get("proxy") is not None]
            cell["median_proxy"] = float(np.median([r["proxy"] for r in sel])) if sel else None
            cell["median_reference_proxy"] = float(np.median(refs)) if refs else None
            summary[attr].append(cell)
            md.append(
                f"| {edges[b]:.3g}-{edges[b + 1]:.3g} | {len(sel)} | "
                + " | ".join(str(cell[key]) for key, _, _ in ATTRIBUTED_SCORES)
                + f" | {cell['reference_collisions']} | {fmt(cell['median_proxy'])} / {fmt(cell['median_reference_proxy'])} |"
            )
        md.append("")
        d = np.array(
            [r["proxy"] - (_ref(r).get("proxy") if _ref(r).get("proxy") is not None else np.nan) for r in rows]
        )
        coll = np.array([_perception_collision(r) for r in rows])
        ax.scatter(v[~coll], d[~coll], s=6, alpha=0.5, label="proxy - reference proxy")
        ax.scatter(v[coll], d[coll], s=14, color="tab:red", label="perception collision")
        ax.axhline(1.0, color="grey", lw=0.8, ls="--")
        ax.set_xlabel(attr)
        ax.set_ylabel("proxy under test - reference")
        ax.grid(alpha=0.3)
    axes[0][0].legend(fontsize=7)
    hit = obstacles_hit(rows)
    if hit:
        summary["obstacle_hit"] = hit
        md += [
            "Collisions of the stack under test by the obstacle it hit (exports from issue #27 on name it):",
            "",
            "| obstacle hit | collisions | perception collisions (the reference drove through) |",
            "|---|---|---|",
            *(f"| {m} | {c['collisions']} | {c['perception_collisions']} |" for m, c in hit.items()),
            "",
        ]
    fig.suptitle(
        f"{what.capitalize()}: what the U-Net stack does worse than the ground-truth stack, by attribute", fontsize=9
    )
    fig.tight_layout()
    fig.savefig(os.path.join(out, figure), dpi=100)
    plt.close(fig)
    return summary, md


def condition_table(base: str, section: dict, out: str):
    """Issue #27: one stack's random-layout baselines (docs/baseline.md) under several conditions
    whose layouts share their obstacle positions (paired: the experiments differ only in what
    else they free), each run beside the ground-truth stack: collisions, the perception's (the
    ground-truth stack reached the goal on the same layout), and those by the obstacle hit; a
    bar figure of the perception collisions by obstacle. Rows: {label: {experiment, stack,
    ground_truth}} with paths relative to the manifest; `layouts` caps every row."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from asg_agent.campaign.experiment import load_experiment

    def rows_of(rel):
        with open(os.path.join(base, rel)) as f:
            return {r["layout"]: r for r in map(json.loads, f) if r["layout"] < n}

    n = int(section.get("layouts", 300))
    summary, md, meshes_seen = {}, [], []
    for label, spec in section["rows"].items():
        exp = load_experiment(os.path.join(base, spec["experiment"]))
        names = [l["mesh_name"] for l in exp.scenario["structural"]["layouts"]]
        test, gt = rows_of(spec["stack"]), rows_of(spec["ground_truth"])
        if set(test) != set(gt):
            raise ValueError(f"{label}: the stack's and the ground truth's layouts differ ({len(test)} / {len(gt)})")
        coll = [r for r in test.values() if r["termination"] == "COLLISION"]
        perc = [r for r in coll if gt[r["layout"]]["termination"] == "SUCCESS"]
        by_mesh: Dict[str, int] = {}
        for r in perc:
            m = names[int(r["collision_with"].split(":")[0])] if r.get("collision_with") else "unknown"
            by_mesh[m] = by_mesh.get(m, 0) + 1
            if m not in meshes_seen:
                meshes_seen.append(m)
        summary[label] = {
            "experiment": spec["experiment"],
            "layouts": len(test),
            "collisions": len(coll),
            "perception_collisions": len(perc),
            "by_obstacle": by_mesh,
            "ground_truth_collisions": sum(r["termination"] == "COLLISION" for r in gt.values()),
        }
    stack = section.get("stack", "the stack under test")
    md += [
        "",
        f"### `{stack}` on the same random obstacle layouts, by condition (issue #27: paired baselines, "
        f"{n} layouts each)",
        "",
        "| condition | experiment | collisions | perception collisions (ground truth drove through) | "
        + " | ".join(f"of them {m}" for m in meshes_seen)
        + " | ground-truth collisions |",
        "|---|---|---|---|" + "---|" * len(meshes_seen) + "---|",
    ]
    for label, c in summary.items():
        md.append(
            f"| {label} | {os.path.basename(c['experiment'])} | {c['collisions']} "
            f"({100 * c['collisions'] / max(1, c['layouts']):.1f} %) | {c['perception_collisions']} | "
            + " | ".join(str(c["by_obstacle"].get(m, 0)) for m in meshes_seen)
            + f" | {c['ground_truth_collisions']} |"
        )
    md.append("")
    fig, ax = plt.subplots(figsize=(7.0, 3.6))
    x = np.arange(len(summary))
    bottom = np.zeros(len(summary))
    for m in meshes_seen:
        v = np.array([100.0 * c["by_obstacle"].get(m, 0) / max(1, c["layouts"]) for c in summary.values()])
        ax.bar(x, v, 0.6, bottom=bottom, label=m)
        bottom += v
    ax.set_xticks(x, list(summary), fontsize=8)
    ax.set_ylabel("perception collisions [% of layouts]")
    ax.set_title(f"{stack} on {n} paired random layouts: where the ground-truth stack drove through", fontsize=9)
    ax.legend(fontsize=8)
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(out, section.get("figure", "conditions.png")), dpi=100)
    plt.close(fig)
    return summary, md


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


def scenario_of(campaign: dict, row: dict) -> dict:
    """The request of an exported row: the experiment's fixed attributes with its positions (and
    its textural attributes, where the export has them)."""
    from asg_scenario.layout import with_positions
    from asg_agent.campaign.experiment import load_experiment

    exp = load_experiment(os.path.join(REPO, "experiments", campaign["experiment"] + ".yaml"))
    s = with_positions(exp.scenario, row["positions"])
    s["textural"].update(row.get("textural") or {})
    return s


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


def table2_attributed(load, section: dict, out: str):
    """Round 3's Table 2 (issue #25): per experiment one attributed TD3-PER-ASP campaign, its
    counts of proxy >= 3 and >= 4 (each split into the perception's, reference < 2, and the
    stack's, reference >= 3), the largest, per 1,000, perception collisions, beside the paper's
    row; and each campaign's rank-1 and rank-2 perception-attributable scenarios (rank_figures)."""
    summary, md = {}, []
    if not section:
        return summary, md
    md += [
        "",
        "### Table 2 on the fixed stack (round 3: TD3-PER-ASP, flawed U-Net, every scenario attributed)",
        "",
        "| experiment | scenarios | proxy >= 3: all / perception's / stack's | >= 4: all / perception's / stack's "
        "| largest | per 1,000: >= 3 / >= 4 | perception collisions | paper (of 5,000): >= 3 / >= 4 / largest "
        "| paper per 1,000 | wall time |",
        "|" + "---|" * 10,
    ]
    for exp, rel in section.items():
        camp, rows = load(rel)
        c = counts(rows)
        n = c["scenarios"]
        split = {}
        for level in (3.0, 4.0):
            sel = [r for r in rows if r["proxy"] is not None and r["proxy"] >= level]
            refp = [_ref(r).get("proxy") for r in sel]
            split[level] = (
                len(sel),
                sum(q is not None and q < REFERENCE_CLEAR for q in refp),
                sum(q is not None and q >= FINDING for q in refp),
            )
        hours = active_hours(rows)
        p = PAPER.get(exp)
        ranks = rank_figures(camp, rows, os.path.join(out, f"table2_{exp}_rank"))
        summary[exp] = dict(
            c, export=rel, hours=hours, ge3_split=list(split[3.0]), ge4_split=list(split[4.0]), ranks=ranks
        )
        md.append(
            f"| {exp} | {n} | {' / '.join(map(str, split[3.0]))} | {' / '.join(map(str, split[4.0]))} | "
            f"{fmt(c['max_proxy'])} | {1000 * split[3.0][0] / n:.0f} / {1000 * split[4.0][0] / n:.0f} | "
            f"{c.get('perception_collisions', '-')} | "
            + (
                f"{p[0]} / {p[1]} / {p[2]:.2f} | {1000 * p[0] / PAPER_SCENARIOS:.0f} / "
                f"{1000 * p[1] / PAPER_SCENARIOS:.0f}"
                if p
                else "- | -"
            )
            + f" | {fmt(hours * 60 if hours else None, '.0f')} min |"
        )
    md.append("")
    return summary, md


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


DIFF_MARGINS = (DIFFERENTIAL, 2.0, 3.0)  # a regression: the stack under test's proxy exceeds the reference's by this


def differential(campaign: dict, rows, test: str, ref: str, top_png: str, curve_png: str, window: int = 100) -> dict:
    """What a differential campaign found. Each row holds both runs of one scenario: the stack
    under test's proxy and terms, and the reference stack's (`reference`); the reward is their
    difference. Counts regressions (reward >= each of DIFF_MARGINS), the reverse, how often the two
    runs score the same, how the proxy >= 3 verdicts of the two stacks cross, the top 10 by reward
    with their terms and terminations, and the rate per window of scenarios (did the search learn
    where the two stacks differ?); draws the rank-1 scenario with both trajectories and the count
    of regressions against scenarios spent."""
    both = sorted((r for r in rows if r["reward"] is not None and r.get("reference")), key=lambda r: r["job"])
    rw = np.array([r["reward"] for r in both])
    pt = np.array([r["proxy"] for r in both])
    pr = np.array([r["reference"]["proxy"] for r in both])
    out = {
        "scenarios": len(rows),
        "both_runs": len(both),
        "under_test": test,
        "reference": ref,
        "same": int((np.abs(rw) < 0.01).sum()),
        "regressions": {f"{m:g}": int((rw >= m).sum()) for m in DIFF_MARGINS},
        "reverse": {f"{m:g}": int((rw <= -m).sum()) for m in DIFF_MARGINS},
        "max_reward": float(rw.max()) if len(rw) else None,
        "min_reward": float(rw.min()) if len(rw) else None,
        "mean_reward": float(rw.mean()) if len(rw) else None,
        "cross": {
            "test_ge3_ref_lt3": int(((pt >= FINDING) & (pr < FINDING)).sum()),
            "test_lt3_ref_ge3": int(((pt < FINDING) & (pr >= FINDING)).sum()),
            "both_ge3": int(((pt >= FINDING) & (pr >= FINDING)).sum()),
            "neither": int(((pt < FINDING) & (pr < FINDING)).sum()),
        },
        "terminations": {},
        "windows": [],
        "top": [],
    }
    for r in both:
        if r["reward"] >= DIFF_MARGINS[0]:
            key = f"{r['termination']} / {r['reference']['termination']}"
            out["terminations"][key] = out["terminations"].get(key, 0) + 1
    for i in range(0, len(both), window):
        w = rw[i : i + window]
        out["windows"].append(
            {
                "from": i + 1,
                "to": i + len(w),
                "mean_reward": float(w.mean()),
                "regressions_1": int((w >= 1).sum()),
                "reverse_1": int((w <= -1).sum()),
                "same": int((np.abs(w) < 0.01).sum()),
            }
        )
    for r in sorted(both, key=lambda r: -r["reward"])[:10]:
        f = r["reference"]
        out["top"].append(
            {
                "job": r["job"],
                "reward": r["reward"],
                "test": {k: r[k] for k in ("proxy", "vis", "yaw_term", "plr", "termination", "sim_time")},
                "ref": {k: f.get(k) for k in ("proxy", "vis", "yaw_term", "plr", "termination", "sim_time")},
            }
        )
    out["divergence"] = divergence(campaign, both)
    if both:
        r = max(both, key=lambda r: r["reward"])
        f = r["reference"]
        req = scenario_of(campaign, r)
        from asg_scenario.report import plot_run
        from asg_agent.scoring.proxy import optimal_path, placed_mask

        opt = optimal_path(req, placed_mask(req, r.get("removed") or []))
        title = (
            f"{campaign['name']}, rank 1 by proxy difference (job {r['job']})\n{test}: proxy {r['proxy']:.2f} "
            f"(yaw {r['yaw_term']:.2f}, PLR {r['plr']:.3f}), {r['termination']}\n{ref}: proxy {f['proxy']:.2f} "
            f"(yaw {f['yaw_term']:.2f}, PLR {f['plr']:.3f}), {f['termination']}"
        )
        plot_run(
            top_png,
            req,
            r["trajectory_xy"],
            title=title,
            optimal=opt.points,
            label=test,
            removed={(l, i) for l, i, *_ in (r.get("removed") or [])},
            others=[(f"{ref} (reference)", f["trajectory_xy"], "tab:green")],
        )
        out["top_figure"] = os.path.basename(top_png)
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6.4, 3.6))
        x = np.arange(1, len(rw) + 1)
        for m in DIFF_MARGINS:
            ax.plot(x, np.cumsum(rw >= m), label=f"{test} worse by >= {m:g}")
        ax.plot(x, np.cumsum(rw <= -DIFF_MARGINS[0]), "--", color="0.4", label=f"{ref} worse by >= {DIFF_MARGINS[0]:g}")
        ax.set_xlabel("scenarios spent (each run on both stacks)")
        ax.set_ylabel("count")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
        ax.set_title(f"{campaign['name']}: proxy({test}) - proxy({ref})", fontsize=9)
        fig.tight_layout()
        fig.savefig(curve_png, dpi=120)
        plt.close(fig)
    return out


def shadow_ahead(req: dict, xy: np.ndarray, i: int, reach: float = 20.0, half_width: float = 5.0) -> bool:
    """Whether an obstacle's cast shadow lies in the corridor `reach` m ahead of trajectory point i
    (heading from the point 1 s later), `half_width` m to either side: ground the camera sees."""
    from asg_scenario.votes import in_cast_shadow

    j = min(len(xy) - 1, i + 10)
    h = xy[j] - xy[i] if j > i else xy[i] - xy[max(0, i - 10)]
    if np.linalg.norm(h) < 1e-6:
        return False
    h = h / np.linalg.norm(h)
    n = np.array([-h[1], h[0]])
    return any(
        in_cast_shadow(req, *(xy[i] + a * h + b * n))
        for a in np.arange(1.0, reach + 0.5, 1.0)
        for b in np.arange(-half_width, half_width + 0.5, 1.0)
    )


def divergence(campaign: dict, rows, gap: float = 0.5, lead: int = 20, seed: int = 0) -> dict:
    """Where the two runs of a differential campaign part: the first 10 Hz sample at which the
    stacks' positions are more than `gap` m apart. Counts, by the sign of the difference, how often
    an obstacle's cast shadow lay ahead of the vehicle `lead` samples (2 s) before that point, and
    the same share at a random sample of the runs that never part (a control: how common shadows
    ahead are anyway)."""
    rng = np.random.default_rng(seed)
    out = {"parted": 0, "never": 0, "by_sign": {}, "control": {"samples": 0, "shadow_ahead": 0}}
    for r in rows:
        if r["reward"] is None or not r.get("reference"):
            continue
        a = np.asarray(r["trajectory_xy"], float)
        b = np.asarray(r["reference"]["trajectory_xy"], float)
        n = min(len(a), len(b))
        far = np.nonzero(np.linalg.norm(a[:n] - b[:n], axis=1) > gap)[0]
        req = scenario_of(campaign, r)
        if not len(far):
            out["never"] += 1
            if n > 1:
                out["control"]["samples"] += 1
                out["control"]["shadow_ahead"] += shadow_ahead(req, a, int(rng.integers(0, n - 1)))
            continue
        out["parted"] += 1
        sign = (
            "test worse by >= 1"
            if r["reward"] >= 1
            else ("reference worse by >= 1" if r["reward"] <= -1 else "within 1")
        )
        e = out["by_sign"].setdefault(sign, {"pairs": 0, "shadow_ahead": 0, "parted_at_m": []})
        e["pairs"] += 1
        i = max(0, int(far[0]) - lead)
        e["shadow_ahead"] += shadow_ahead(req, a, i)
        e["parted_at_m"].append(float(np.linalg.norm(np.diff(a[: far[0] + 1], axis=0), axis=1).sum()))
    for e in out["by_sign"].values():
        e["median_parted_at_m"] = float(np.median(e.pop("parted_at_m")))
    return out


def differential_tables(campaign: dict, d: dict) -> List[str]:
    t, f = d["under_test"], d["reference"]
    md = [
        "",
        f"### Differential campaign ({campaign['name']}: {t} under test, {f} as reference, "
        f"reward = proxy({t}) - proxy({f}))",
        "",
        f"| scenarios (both runs) | same proxy (within 0.01) | {t} worse by >= 1 / 2 / 3 | {f} worse by >= 1 / 2 / 3 "
        f"| largest difference | mean | {t} >= 3, {f} < 3 | {f} >= 3, {t} < 3 | both >= 3 |",
        "|" + "---|" * 9,
        f"| {d['both_runs']} (of {d['scenarios']}) | {d['same']} | "
        + " / ".join(str(v) for v in d["regressions"].values())
        + " | "
        + " / ".join(str(v) for v in d["reverse"].values())
        + f" | {fmt(d['max_reward'])} | {fmt(d['mean_reward'], '+.3f')} | "
        f"{d['cross']['test_ge3_ref_lt3']} | {d['cross']['test_lt3_ref_ge3']} | {d['cross']['both_ge3']} |",
        "",
        f"Terminations ({t} / {f}) of the scenarios where {t} is worse by >= 1: "
        + (", ".join(f"{k} {v}" for k, v in sorted(d["terminations"].items(), key=lambda kv: -kv[1])) or "none")
        + ".",
        "",
        f"Where the two runs part (first point more than 0.5 m apart): {d['divergence']['parted']} pairs part, "
        f"{d['divergence']['never']} drive the same path. An obstacle's cast shadow lay within 20 m ahead (10 m "
        "wide corridor) 2 s before they part in:",
        "",
        "| pairs that part | pairs | shadow ahead 2 s before parting | median distance driven when they part |",
        "|---|---|---|---|",
    ]
    for sign, e in sorted(d["divergence"]["by_sign"].items()):
        md.append(
            f"| {sign.replace('test', t).replace('reference', f)} | {e['pairs']} | {e['shadow_ahead']} "
            f"({100 * e['shadow_ahead'] / e['pairs']:.0f}%) | {e['median_parted_at_m']:.1f} m |"
        )
    c = d["divergence"]["control"]
    md += [
        f"| control: a random point of the pairs that never part | {c['samples']} | {c['shadow_ahead']} "
        + (f"({100 * c['shadow_ahead'] / c['samples']:.0f}%)" if c["samples"] else "")
        + " | - |",
        "",
        f"| scenarios | mean difference | {t} worse by >= 1 | {f} worse by >= 1 | same proxy |",
        "|---|---|---|---|---|",
    ]
    for w in d["windows"]:
        md.append(
            f"| {w['from']}-{w['to']} | {w['mean_reward']:+.3f} | {w['regressions_1']} | {w['reverse_1']} | {w['same']} |"
        )
    md += [
        "",
        f"| job | difference | {t}: proxy (vis, yaw term, PLR), end | {f}: proxy (vis, yaw term, PLR), end |",
        "|---|---|---|---|",
    ]
    for r in d["top"]:
        cells = []
        for s in (r["test"], r["ref"]):
            cells.append(
                f"{fmt(s['proxy'])} ({fmt(s['vis'], '+.2f')}, {fmt(s['yaw_term'])}, {fmt(s['plr'], '.3f')}), "
                f"{s['termination']} at {fmt(s['sim_time'], '.1f')} s"
            )
        md.append(f"| {r['job']} | {r['reward']:+.2f} | {cells[0]} | {cells[1]} |")
    return md


def differential_section(load, spec, out: str, prefix: str):
    """(summary, table lines) of one differential campaign: spec is an export path or {export,
    under_test, reference} (the stacks' names as the tables print them); figures OUT/PREFIX_top.png
    and OUT/PREFIX_curve.png."""
    spec = {"export": spec} if isinstance(spec, str) else dict(spec)
    camp, rows = load(spec["export"])
    d = differential(
        camp,
        rows,
        spec.get("under_test", "under test"),
        spec.get("reference", "reference"),
        os.path.join(out, f"{prefix}_top.png"),
        os.path.join(out, f"{prefix}_curve.png"),
    )
    d["export"] = spec["export"]
    return d, differential_tables(camp, d)


def flaw_or_layout_attributed(load, base: str, section: dict):
    """(summary, table lines) of round 3's flaw or layout: what an attributed campaign blamed on
    the perception (`asg_agent.ros.rerun --select perception`), re-run on other stacks and grids;
    per class of the campaign's verdict, how many fail the same way again, and the collisions
    split by the obstacle the campaign's run hit. section: {file: R.json (rerun summary's; its
    re-runs in the folder R/), campaign: NAME (the heading's), export: the campaign's export}."""
    from asg_agent.scoring.attribution import RERUN_CLASSES as CLASSES, still_failing

    with open(os.path.join(base, section["file"])) as f:
        rows = json.load(f)["summary"]
    hit = {}
    if section.get("export"):
        _, crows = load(section["export"])
        hit = {r["job"]: r["meshes"][r["collision_with"]] for r in crows if r.get("collision_with") is not None}
    folder = os.path.join(base, os.path.splitext(section["file"])[0])
    for s in rows:
        by_mesh = {}
        path = os.path.join(folder, s["file"])
        if hit and os.path.exists(path):
            with open(path) as f:
                for r in (json.loads(line) for line in f if line.strip()):
                    if r.get("campaign_class") == "collision" and r["job"] in hit:
                        e = by_mesh.setdefault(hit[r["job"]], {"runs": 0, "still": 0})
                        e["runs"] += 1
                        e["still"] += still_failing(r)
        s["collisions_by_obstacle"] = by_mesh
    label = {
        "finding": "perception findings: still >= 3",
        "differential": "differential: still >= 1 over the reference",
        "collision": "perception collisions: collides again",
    }
    md = [
        "",
        f"### Flaw or layout, round 3 (what {section.get('campaign', 'the campaign')} blamed on the perception, re-run)",
        "",
        "| planner grid | stack | re-run | "
        + " | ".join(label[c] for c in CLASSES)
        + " | collides again, by the obstacle the campaign's run hit | errors |",
        "|" + "---|" * (5 + len(CLASSES)),
    ]
    for s in sorted(rows, key=lambda s: (s["grid"] != "paper", s["grid"], s["stack"])):
        cells = []
        for c in CLASSES:
            e = (s.get("by_class") or {}).get(c)
            cells.append(f"{e['still']} of {e['runs']}" if e else "-")
        cells.append(
            ", ".join(f"{m} {e['still']} of {e['runs']}" for m, e in sorted(s["collisions_by_obstacle"].items())) or "-"
        )
        md.append(f"| {s['grid']} | {s['stack']} | {s['runs']} | " + " | ".join(cells) + f" | {s['errors']} |")
    return rows, md


def fmt(v, spec=".2f"):
    return "-" if v is None else format(v, spec)


def run(manifest_path: str, out: str) -> dict:
    base = os.path.dirname(os.path.abspath(manifest_path))
    with open(manifest_path) as f:
        man = yaml.safe_load(f) or {}
    os.makedirs(out, exist_ok=True)
    cache: Dict[str, tuple] = {}

    def load(rel):
        if rel not in cache:
            cache[rel] = read_export(os.path.join(base, rel))
        return cache[rel]

    summary, md = {"table2": {}, "comparison": {}, "diversity": {}}, []
    # -- round 3: searches on the fixed stack, attributed ------------------------------------------
    if (man.get("attributed") or {}).get("arms"):
        summary["attributed"], lines = attributed_comparison(load, man["attributed"], out)
        md += lines[1:]
    if man.get("table2_attributed"):
        summary["table2_attributed"], lines = table2_attributed(load, man["table2_attributed"], out)
        md += lines
    if (man.get("weather") or {}).get("exports"):
        summary["weather"], lines = weather_tables(load, man["weather"], out)
        md += lines[1:]
    if (man.get("terrain") or {}).get("exports"):
        summary["terrain"], lines = weather_tables(load, man["terrain"], out, "terrain and weather", "terrain.png")
        md += lines[1:]
    if (man.get("conditions") or {}).get("rows"):
        summary["conditions"], lines = condition_table(base, man["conditions"], out)
        md += lines
    if (man.get("flaw_or_layout_attributed") or {}).get("file"):
        summary["flaw_or_layout_attributed"], lines = flaw_or_layout_attributed(
            load, base, man["flaw_or_layout_attributed"]
        )
        md += lines
    for spec in man.get("differentials") or []:
        prefix = spec.get("figures") or os.path.basename(spec["export"]).split(".")[0]
        summary.setdefault("differentials", {})[prefix], lines = differential_section(load, spec, out, prefix)
        md += lines
    if man.get("attributed") or man.get("weather") or man.get("terrain"):
        md += ["", "## Round 2 (the stiff follower; stale, kept for the record)", ""]
    # -- Table 2 ---------------------------------------------------------------------------------
    if man.get("table2"):
        md += [
            "### Table 2",
            "",
            "| experiment | scenarios | proxy >= 3 | >= 4 | largest | per 1,000: >= 3 / >= 4 "
            "| paper (of 5,000): >= 3 / >= 4 / largest | paper per 1,000 | wall time | workers |",
            "|" + "---|" * 10,
        ]
    for exp, rel in (man.get("table2") or {}).items():
        camp, rows = load(rel)
        c = counts(rows)
        hours = active_hours(rows)
        workers = len(json.loads(camp["settings"]).get("workers", [])) if camp.get("settings") else None
        p = PAPER.get(exp)
        summary["table2"][exp] = dict(c, export=rel, hours=hours)
        n = c["scenarios"]
        md.append(
            f"| {exp} | {n} | {c['proxy_ge_3']} | {c['proxy_ge_4']} | {fmt(c['max_proxy'])} | "
            f"{1000 * c['proxy_ge_3'] / n:.0f} / {1000 * c['proxy_ge_4'] / n:.0f} | "
            + (
                f"{p[0]} / {p[1]} / {p[2]:.2f} | {1000 * p[0] / PAPER_SCENARIOS:.0f} / "
                f"{1000 * p[1] / PAPER_SCENARIOS:.0f}"
                if p
                else "- | -"
            )
            + f" | {fmt(hours * 60 if hours else None, '.0f')} min | {workers or '-'} |"
        )
        summary["table2"][exp]["top"] = top_figure(camp, rows, os.path.join(out, f"top_{exp}.png"))
    # -- search comparison -----------------------------------------------------------------------
    comp = man.get("comparison") or {}
    budget = int(comp.get("budget", 1000))
    thr = float((man.get("diversity") or {}).get("threshold_m", 5.0))
    curves = {}
    if comp.get("arms"):
        md += [
            "",
            f"### Search comparison (Exp. 1, flawed U-Net, budget {budget} scenarios per run)",
            "",
            "| method | runs (seeds) | proxy >= 3 at the budget: each run | mean | min-max | vs random (mean) "
            f"| of which in scenarios {budget // 2 + 1}-{budget}: each run "
            f"| distinct layouts among them ({thr:g} m, in the order found): each run | mean |",
            "|---|---|---|---|---|---|---|---|---|",
        ]
        for arm, rels in comp["arms"].items():
            curves[arm] = []
            for rel in rels:
                camp, rows = load(rel)
                cv = ge3_curve(rows, budget)
                curves[arm].append(
                    {
                        "seed": camp["seed"],
                        "scenarios": len(cv),
                        "curve": cv,
                        "distinct": distinct_curve(rows, budget, thr),
                    }
                )
        rnd = [c["curve"][-1] for c in curves.get("random", []) if c["scenarios"] >= budget]
        rnd_mean = float(np.mean(rnd)) if rnd else None
        for arm, runs in curves.items():
            full = [int(r["curve"][-1]) for r in runs if r["scenarios"] >= budget]
            short = [
                f"{int(r['curve'][-1])} (s{r['seed']}, only {r['scenarios']})" for r in runs if r["scenarios"] < budget
            ]
            mean = float(np.mean(full)) if full else None
            summary["comparison"][arm] = {
                "runs": [
                    {
                        "seed": r["seed"],
                        "scenarios": r["scenarios"],
                        "ge3": int(r["curve"][-1]),
                        "distinct_ge3": int(r["distinct"][-1]),
                        "ge3_second_half": (
                            int(r["curve"][-1] - r["curve"][budget // 2 - 1]) if r["scenarios"] >= budget else None
                        ),
                    }
                    for r in runs
                ],
                "mean_at_budget": mean,
            }
            md.append(
                f"| {arm} | {len(full)} ({', '.join(str(r['seed']) for r in runs)}) | "
                f"{', '.join(str(v) for v in full + short)} | {fmt(mean, '.1f')} | "
                + (f"{min(full)}-{max(full)}" if full else "-")
                + " | "
                + (f"{mean / rnd_mean:.2f}x" if mean is not None and rnd_mean else "-")
                + " | "
                + ", ".join(
                    str(int(r["curve"][-1] - r["curve"][budget // 2 - 1])) for r in runs if r["scenarios"] >= budget
                )
                + " | "
                + ", ".join(str(int(r["distinct"][-1])) for r in runs)
                + " | "
                + fmt(np.mean([r["distinct"][-1] for r in runs if r["scenarios"] >= budget]) if full else None, ".1f")
                + " |"
            )
        comparison_figure(curves, budget, thr, os.path.join(out, "search_comparison.png"))
        # Where every run placed its obstacles as it went (the summary keeps each arm's first).
        dyn = {}
        for arm, rels in comp["arms"].items():
            for k, rel in enumerate(rels):
                camp, rows = load(rel)
                dyn[(arm, k)] = (camp["name"], dynamics(camp, rows, budget))
        summary["dynamics"] = {arm: d for (arm, k), (_, d) in dyn.items() if k == 0}
        names = list(dyn)
        md += [
            "",
            "### Search dynamics (every run, per 100 scenarios: proxy >= 3 / obstacles "
            "within 2 m of the edge / median distance of obstacles from the start-goal line)",
            "",
            "| scenarios | " + " | ".join(f"{dyn[a][0]}" for a in names) + " |",
            "|---|" + "---|" * len(names),
        ]
        for k in range(max(len(d) for _, d in dyn.values())):
            cells = []
            for a in names:
                d = dyn[a][1]
                cells.append(
                    f"{d[k]['ge3']} / {100 * d[k]['at_edge']:.0f}% / {d[k]['median_to_route_m']:.1f} m"
                    + ("" if d[k]["to"] - d[k]["from"] == 99 else f" (of {d[k]['to'] - d[k]['from'] + 1})")
                    if k < len(d)
                    else "-"
                )
            md.append(f"| {k * 100 + 1}-{(k + 1) * 100} | " + " | ".join(cells) + " |")
    # -- diversity -------------------------------------------------------------------------------
    div = man.get("diversity") or {}
    if div.get("arms") and curves:
        top, thr = int(div.get("top", 100)), float(div.get("threshold_m", 5.0))
        thrs = [float(t) for t in div.get("all_thresholds_m", [thr])]
        md += [
            "",
            "### Diversity (a layout is distinct when its mean matched displacement from every higher-ranked "
            "distinct one exceeds the threshold)",
            "",
            "| method | run | distinct among the top %d at %g m | of which proxy >= 3 | proxy >= 3 in all "
            "| distinct among all with proxy >= 3, at %s m |" % (top, thr, " / ".join(f"{t:g}" for t in thrs)),
            "|---|---|---|---|---|---|",
        ]
        for arm in div["arms"]:
            for rel in (comp["arms"].get(arm) or [])[:1]:
                camp, rows = load(rel)
                rows = sorted(rows, key=lambda r: r["job"])[:budget]
                n = distinct(rows, top, thr)
                ge3 = sum((r["proxy"] or 0) >= FINDING for r in rows)
                n3 = {f"{t:g}": distinct(rows, None, t, min_proxy=FINDING) for t in thrs}
                summary["diversity"][arm] = {
                    "export": rel,
                    "distinct": n,
                    "top": min(top, len(rows)),
                    "ge3": ge3,
                    "distinct_ge3": n3,
                }
                md.append(
                    f"| {arm} | {camp['name']} | {n} | {min(top, ge3)} | {ge3} | "
                    + " / ".join(str(v) for v in n3.values())
                    + " |"
                )
    # -- flaw or layout, differential ------------------------------------------------------------
    if man.get("flaw_or_layout") and os.path.exists(os.path.join(base, man["flaw_or_layout"])):
        with open(os.path.join(base, man["flaw_or_layout"])) as f:
            fol = json.load(f)
        summary["flaw_or_layout"] = fol["summary"]
        md += [
            "",
            "### Flaw or layout (the top scenarios of the Exp. 1 campaign, re-run)",
            "",
            "| planner grid | stack | re-run | still >= 3 | dropped below 3 | median proxy (campaign's: flawed, paper grid) |",
            "|---|---|---|---|---|---|",
        ]
        for s in fol["summary"]:
            md.append(
                f"| {s['grid']} | {s['stack']} | {s['runs']} | {s['still_ge3']} | {s['dropped']} | "
                f"{fmt(s.get('median_proxy'))} ({fmt(s.get('campaign_median_proxy'))}) |"
            )
    if man.get("differential"):
        summary["differential"], lines = differential_section(load, man["differential"], out, "differential")
        md += lines
    with open(os.path.join(out, "tables.md"), "w") as f:
        f.write(
            "<!-- generated by `python3 -m asg_agent.analysis.experiments`; do not edit -->\n" + "\n".join(md) + "\n"
        )
    with open(os.path.join(out, "summary.json"), "w") as f:
        json.dump(summary, f, indent=1, sort_keys=True)
    return summary


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


BEGIN, END = "<!-- tables:begin -->", "<!-- tables:end -->"


def docs_block(text: str) -> str:
    """The generated tables as docs/experiments.md quotes them."""
    if BEGIN not in text or END not in text:
        raise ValueError(f"no {BEGIN} ... {END} block")
    return text.split(BEGIN, 1)[1].split(END, 1)[0].strip("\n")


def update_docs(path: str, tables: str):
    with open(path) as f:
        text = f.read()
    docs_block(text)
    head, rest = text.split(BEGIN, 1)
    with open(path, "w") as f:
        f.write(head + BEGIN + "\n" + tables.strip("\n") + "\n" + END + rest.split(END, 1)[1])


def main(argv=None):
    p = argparse.ArgumentParser(prog="asg_agent.analysis.experiments", description=__doc__.split("\n\n")[0])
    p.add_argument("--manifest", default=os.path.join(REPO, "results", "experiments.yaml"))
    p.add_argument("--out", default=os.path.join(REPO, "docs", "experiments"))
    p.add_argument(
        "--docs",
        default=os.path.join(REPO, "docs", "experiments.md"),
        help="rewrite the block between the tables markers of this file ('' to leave it)",
    )
    a = p.parse_args(argv)
    try:
        run(a.manifest, a.out)
    except (OSError, ValueError, KeyError) as e:
        print(f"experiments: {e}", file=sys.stderr)
        return 2
    with open(os.path.join(a.out, "tables.md")) as f:
        tables = f.read()
    print(tables)
    if a.docs and os.path.exists(a.docs):
        update_docs(a.docs, tables)
    print(f"written: {a.out}/tables.md, summary.json and figures", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
