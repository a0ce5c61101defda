"""What a search learned (issue #67, no ROS): for each obstacle attribute, its share among the
obstacles of the layouts the search proposed, against its share among the obstacles of its flaw
findings and among the obstacles those findings hit, early and late in the budget.

A search that learns what exposes the flaw proposes, late in its budget, more of the obstacles
that flaw findings are made of; one that does not keeps its early shares. The attributes are what
the scene says of each obstacle, computed here apart from any search method's own features:

- `class`: its mesh;
- `beside`: how far from the straight start-goal line, in bands of LATERAL_BANDS [m];
- `along`: which quarter of the way from start to goal;
- `shaded`: whether it stands in the sun shadow of another obstacle (asg_scenario.votes);
- `class, beside`: both at once (every layout holds each class in the scenario's counts, so a
  class's share among the obstacles of any layout is fixed; where each class stands is not).

    python3 -m asg_analysis learned results/flaw_study3 flaw3-pilot-surrogate-wide-s20 [...] \
        [--budget 250] [--target flaw] [--json out.json] [--markdown] [--figure out.png]

Each campaign is split at half its budget (jobs below budget / 2: early; the rest: late), or at
`--split N` (e.g. where a search's uniform start ends); the shares pool the campaigns given.
"""

import argparse
import os
import sys
from typing import Dict, List

import numpy as np

PROG = "python3 -m asg_analysis learned"

#: [m] the `beside` bands' upper edges, the last open
LATERAL_BANDS = (2.0, 5.0, 10.0, 20.0)


def _band(d: float) -> str:
    lo = 0.0
    for hi in LATERAL_BANDS:
        if d < hi:
            return f"{lo:g}-{hi:g} m"
        lo = hi
    return f">= {lo:g} m"


def obstacle_attributes(campaign: dict, row: dict) -> List[Dict[str, str]]:
    """Each obstacle's attributes (class, beside, along, shaded) of an export row."""
    from asg_agent.records.scenes import scenario_of
    from asg_scenario.layout import RouteFrame
    from asg_scenario.votes import in_cast_shadow

    scene = scenario_of(campaign, row)
    f = RouteFrame(scene)
    p = np.asarray(row["positions"], float).reshape(-1, 2)
    t = (p - f.start) @ f.along / f.length**2
    d = np.abs((p - f.start) @ f.normal)
    index = [(li, ii) for li, lay in enumerate(scene["structural"]["layouts"]) for ii in range(len(lay["instances"]))]
    out = []
    for k, mesh in enumerate(row["meshes"]):
        shaded = in_cast_shadow(scene, p[k, 0], p[k, 1], removed={index[k]})
        out.append(
            {
                "class": mesh,
                "beside": _band(d[k]),
                "class, beside": f"{mesh}, {_band(d[k])}",
                "along": f"Q{int(np.clip(t[k] * 4, 0, 3)) + 1}",
                "shaded": "shaded" if shaded else "lit",
            }
        )
    return out


def shares(campaigns: List[tuple], budget: int, target: str = "flaw", split: int = 0) -> dict:
    """{attribute: {value: {proposed_early, proposed_late, findings_early, findings_late,
    hit_early, hit_late}}} over (campaign, rows) pairs, with the obstacle counts under `n`; early
    are the jobs below `split` (0: half the budget)."""
    split = split or budget / 2
    if not 0 < split < budget:
        raise ValueError(f"learned: the split {split} must lie inside the budget {budget}")
    counts: Dict[str, Dict[str, Dict[str, int]]] = {}
    n = {k: 0 for k in ("proposed_early", "proposed_late", "findings_early", "findings_late", "hit_early", "hit_late")}
    for camp, rows in campaigns:
        for r in rows:
            if r["job"] >= budget or not r.get("positions"):
                continue
            half = "early" if r["job"] < split else "late"
            attrs = obstacle_attributes(camp, r)
            groups = [f"proposed_{half}"] + ([f"findings_{half}"] if r.get("attribution") == target else [])
            for g in groups:
                n[g] += len(attrs)
                for a in attrs:
                    for key, value in a.items():
                        counts.setdefault(key, {}).setdefault(value, dict.fromkeys(n, 0))[g] += 1
            hit = r.get("collision_with")
            if r.get("attribution") == target and isinstance(hit, int) and 0 <= hit < len(attrs):
                n[f"hit_{half}"] += 1
                for key, value in attrs[hit].items():
                    counts.setdefault(key, {}).setdefault(value, dict.fromkeys(n, 0))[f"hit_{half}"] += 1
    table = {
        key: {
            value: {g: (c[g] / n[g] if n[g] else None) for g in n}
            for value, c in sorted(values.items(), key=lambda kv: _order(kv[0]))
        }
        for key, values in counts.items()
    }
    return {"shares": table, "n": n, "target": target, "budget": budget, "split": split}


def _order(value: str):
    """Values in reading order: bands by their lower edge, the rest alphabetically."""
    import re

    m = re.search(r"(>= )?(\d+(\.\d+)?)(-\d+(\.\d+)?)? m$", value)
    return (value[: m.start()] if m else value, float(m.group(2)) if m else 0.0)


def _split(res: dict) -> str:
    """Where early ends, in words."""
    s = res.get("split", res["budget"] / 2)
    return (
        f"half the budget of {res['budget']}" if s == res["budget"] / 2 else f"{s:g} of the budget of {res['budget']}"
    )


def _pct(x) -> str:
    return "-" if x is None else f"{100 * x:.0f} %"


def markdown(res: dict) -> str:
    t, n = res["target"], res["n"]
    lines = [
        f"| attribute | value | proposed, early | proposed, late | in {t} findings, early | in {t} findings, late "
        f"| hit by a {t} collision, early | hit, late |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for key in ("class", "beside", "class, beside", "along", "shaded"):
        for value, s in res["shares"].get(key, {}).items():
            lines.append(
                f"| {key} | {value} | {_pct(s['proposed_early'])} | {_pct(s['proposed_late'])} "
                f"| {_pct(s['findings_early'])} | {_pct(s['findings_late'])} | {_pct(s['hit_early'])} "
                f"| {_pct(s['hit_late'])} |"
            )
    lines += [
        "",
        f"Obstacles counted: proposed {n['proposed_early']:,} early, {n['proposed_late']:,} late; in {t} findings "
        f"{n['findings_early']:,} and {n['findings_late']:,}; hit by a {t} collision {n['hit_early']} and "
        f"{n['hit_late']} (early: jobs below {_split(res)}).",
    ]
    return "\n".join(lines)


#: the figure's bars: (share, label), one colour each
FIGURE_BARS = (
    ("proposed_early", "proposed, early"),
    ("proposed_late", "proposed, late"),
    ("findings_late", "in {t} findings, late"),
    ("hit_late", "hit by a {t} collision, late"),
)
FIGURE_PANELS = ("class, beside", "along", "shaded")


def figure(res: dict, out: str) -> Dict[str, List[List[float]]]:
    """One panel of grouped bars per attribute of FIGURE_PANELS: each value's share among the
    obstacles proposed early and late and among those of late findings and late hits. A search
    that learns moves its late proposals towards what its findings hold. Returns the bar heights
    drawn, {panel: [[height per value] per bar]} (a share with no obstacle counted is 0)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = res["target"]
    panels = [k for k in FIGURE_PANELS if res["shares"].get(k)]
    widths = [max(2, len(res["shares"][k])) for k in panels]
    fig, axes = plt.subplots(
        1, len(panels), figsize=(2.0 + 0.55 * sum(widths), 4.2), gridspec_kw={"width_ratios": widths}
    )
    axes = np.atleast_1d(axes)
    drawn = {}
    for ax, key in zip(axes, panels):
        values = list(res["shares"][key])
        x = np.arange(len(values))
        w = 0.8 / len(FIGURE_BARS)
        drawn[key] = []
        for i, (g, label) in enumerate(FIGURE_BARS):
            h = [100 * (res["shares"][key][v][g] or 0.0) for v in values]
            drawn[key].append(h)
            ax.bar(x + (i - (len(FIGURE_BARS) - 1) / 2) * w, h, w, label=label.format(t=t))
        ax.set_xticks(x, values, rotation=60, ha="right", fontsize=8)
        ax.set_title(key, fontsize=10)
        ax.set_ylabel("share of obstacles [%]")
        ax.grid(axis="y", alpha=0.3)
    axes[0].legend(fontsize=8, loc="upper left")
    n = res["n"]
    fig.suptitle(
        f"What the search learned: obstacles proposed ({n['proposed_early']:,} early, {n['proposed_late']:,} late) "
        f"against those of its {t} findings (early: jobs below {_split(res)})",
        fontsize=10,
    )
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return drawn


def run(argv=None) -> int:
    ap = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    ap.add_argument("folder", help="the exports' folder")
    ap.add_argument("campaigns", nargs="+", help="campaign names (NAME.jsonl.gz in the folder)")
    ap.add_argument("--budget", type=int, default=300, help="[scenarios] each campaign's budget (300)")
    ap.add_argument("--target", default="flaw", help="the attribution class of a finding (flaw; regression)")
    ap.add_argument("--json", default="")
    ap.add_argument("--markdown", action="store_true")
    ap.add_argument("--figure", default="", help="a PNG of the shares (class and band, quarter, shade)")
    ap.add_argument(
        "--split", type=int, default=0, help="[scenarios] early: the jobs below this (default: half the budget)"
    )
    a = ap.parse_args(argv)
    from asg_agent.records.export import read_export

    camps = []
    for name in a.campaigns:
        path = os.path.join(a.folder, name + ".jsonl.gz")
        if not os.path.isfile(path):
            print(f"learned: no export {path}", file=sys.stderr)
            return 2
        camps.append(read_export(path))
    try:
        res = shares(camps, a.budget, a.target, a.split)
    except ValueError as e:
        print(str(e), file=sys.stderr)
        return 2
    from asg_analysis.files import report

    return report(res, a.json, figure, a.figure, markdown, a.markdown)
