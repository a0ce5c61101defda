"""Issue #27's tables (docs/experiments.md): findings by textural attribute (weather) and the
paired baselines by condition. No ROS."""

import json
import os
from typing import Dict

import numpy as np

from asg_analysis.studies.attributed_tables import ATTRIBUTED_SCORES
from asg_analysis.campaign_metrics import _perception_collision, _ref, attribute_value, fmt, obstacles_hit


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
    from asg_agent.records.experiment import load_experiment

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
