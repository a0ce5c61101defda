"""Differential campaigns (docs/experiments.md): the stack under test against a reference on the
same scenarios, its tables and figures, and where the two runs part. No ROS."""

import os
from typing import List

import numpy as np

from asg_agent.records.store import DIFFERENTIAL, FINDING
from asg_analysis.campaign_metrics import fmt
from asg_agent.records.scenes import scenario_of, shadow_ahead


DIFF_MARGINS = (DIFFERENTIAL, 2.0, 3.0)  # a regression: the stack under test's proxy exceeds the reference's by this


def regressions_figure(campaign: dict, rw, test: str, ref: str, curve_png: str):
    """The count of regressions (each margin) and of the reverse against scenarios spent."""
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
        regressions_figure(campaign, rw, test, ref, curve_png)
    return out


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
