"""A protocol's pages (no ROS): the status and result blocks of its study record, and its
coverage map, from what asg_analysis.protocol_analysis computes."""

import os
import re
from typing import List, Optional

from asg_agent.paths import REPO
from asg_agent.scoring import rewards as reward_registry
from asg_analysis.protocol import ATTRIBUTION_ROLES
from asg_analysis.protocol_analysis import other_classes


def markers(p: dict):
    """(status begin, status end, result begin, result end) of a protocol's generated blocks in
    its page: "<!-- NAME study status: begin (generated) -->" and so on, NAME the protocol's name."""
    n = p["name"]
    return (
        f"<!-- {n} study status: begin (generated) -->",
        f"<!-- {n} study status: end -->",
        f"<!-- {n} study result: begin (generated) -->",
        f"<!-- {n} study result: end -->",
    )


def _f(x: Optional[float], nd: int = 1) -> str:
    if x is None:
        return ""
    if x != x:  # nan: a ratio of two arms that found none
        return "undefined"
    return "inf" if x == float("inf") else f"{x:.{nd}f}"


def _x(ratio: float) -> str:
    """A ratio of means in prose: "1.60x", or "undefined" where neither arm found any."""
    return _f(ratio, 2) + ("" if ratio != ratio else "x")


#: How the pages name each endpoint class: (plural, short), e.g. "flaw findings", "flaw".
CLASS_LABELS = {"flaw": ("flaw findings", "flaw"), "regression": ("regressions", "regression")}


def class_labels(p: dict):
    cls = p["endpoint"]["class"]
    return CLASS_LABELS.get(cls, (f"{cls} findings", cls))


def question(p: dict) -> str:
    """The study's question, from its endpoint class (the scene is the protocol's, named above it)."""
    what = {
        "flaw": "the injected flaw",
        "regression": "the release candidate's regressions (scenes only it fails)",
    }.get(p["endpoint"]["class"], p["endpoint"]["class"])
    return f"Does the search find {what} better than a sampler that puts obstacles on the route?"


def _plain_answer(t: dict, ref: dict, ref_h: Optional[dict], plural: str = "flaw findings") -> str:
    """The study's question answered from the default's comparison with the target's arm: the
    per-1,000 endpoint decides at the protocol's p; the per-CPU-hour one is said beside it. A
    protocol with `p: null` is descriptive (its seeds cannot reach a test): the answer is the
    ratio of means against the target's, with its interval, and claims no significance."""
    better = ref["ratio"] > 1.0
    if ref["ratio"] != ref["ratio"]:  # nan: neither arm found one
        return (
            f"no: neither the search nor {t['ratio_over']} found any {plural}, so the search had no signal "
            "to learn from and the ratio is undefined"
        )
    if t.get("p") is None:
        answer = (
            f"descriptive, no test (too few seeds to reach one): the default's mean is {_x(ref['ratio'])} "
            f"{t['ratio_over']}'s {plural} per 1,000 ({_f(ref['ratio_lo'], 2)}-{_f(ref['ratio_hi'], 2)})"
        )
        if ref_h:
            answer += f" and {_x(ref_h['ratio'])} per CPU-hour ({_f(ref_h['ratio_lo'], 2)}-{_f(ref_h['ratio_hi'], 2)})"
        return answer
    if ref["p"] < t["p"]:
        answer = (
            f"yes: the search finds more {plural} per 1,000 than {t['ratio_over']}, at p < {t['p']:g}"
            if better
            else f"no: {t['ratio_over']} finds more {plural} per 1,000 than the search, at p < {t['p']:g}"
        )
    else:
        answer = (
            f"not decided at p < {t['p']:g}: the default's mean is {'above' if better else 'below'} "
            f"{t['ratio_over']}'s (Cliff's delta {ref['effect']:+.2f}), but p = {ref['p']:.4f} does not "
            "separate the arms at that level"
        )
    if ref_h:  # the second endpoint, what a user pays for
        ahead = "the search" if ref_h["ratio"] > 1.0 else t["ratio_over"]
        answer += f"; per CPU-hour, {ahead} finds more (p = {ref_h['p']:.4f}, " + (
            f"< {t['p']:g})" if ref_h["p"] < t["p"] else f"not < {t['p']:g})"
        )
    return answer


def _who_runs(args: List[str]) -> str:
    """Whether `bash scripts/train.sh` runs the winner as it is (launch/train.launch's defaults are
    its arguments) or only with them, in words."""
    try:
        with open(os.path.join(REPO, "launch", "train.launch"), encoding="utf-8") as f:
            default = dict(re.findall(r'<arg name="(\w+)" default="([^"]*)"', f.read()))
    except OSError:  # an install space without the repository's launch folder
        default = {}
    given = dict(a.split(":=", 1) for a in args)
    reward = default.get("reward")
    if reward == reward_registry.AUTO:  # what `auto` stands for under the launch file's default attribution
        reward = reward_registry.for_roles(ATTRIBUTION_ROLES.get(default.get("attribution", ""), ()))
    same = (
        default.get("method") == given.get("method")
        and reward == given.get("reward", "proxy")
        and default.get("experiment", "").endswith(os.path.basename(given.get("experiment", "")))
        and default.get("route_band", "") == given.get("route_band", "")
    )
    if same:
        return f"`bash scripts/train.sh` runs it: `{' '.join(args)}`."
    return f"Not `bash scripts/train.sh`'s default; it runs with `bash scripts/train.sh 150 {' '.join(args)}`."


def result_markdown(p: dict, res: dict, figure: str = "", budget: str = "", budget_figure: str = "") -> str:
    """The study's answer as a generated block: the comparison table (per arm: flaw findings per
    1,000 and per CPU-hour with 95 % bootstrap intervals, distinct flaw modes, model and stack
    findings, coverage; the default against each arm: ratio, two-sided Mann-Whitney p and Cliff's
    delta on both endpoints), the target, the winner and a plain answer. Until every confirmatory
    campaign is complete it says how many are, and compares nothing (the protocol's rule)."""
    lines = [markers(p)[2]]
    if p.get("round"):
        lines += [
            f"*Round {p['round']}'s study (protocol version {p['version']}, `{os.path.relpath(os.path.abspath(p['_path']), REPO)}`).*",
            "",
        ]
    if res["complete"] < res["campaigns"]:
        lines += [
            f"**Not answered yet: {res['complete']} of the {res['campaigns']} confirmatory campaigns are "
            "complete.** The protocol compares no arm before all of them are in; this block is "
            "rewritten by `protocol analyse --doc` when they are.",
            markers(p)[3],
        ]
        return "\n".join(lines)
    arms, t = res["arms"], p["target"]
    plural, short = class_labels(p)
    hour = {r["arm"]: r for r in res["comparison_per_cpu_hour"]}
    others = [k for k in other_classes(p["endpoint"]["class"]) if all(k in a for a in arms.values())]  # as analysed
    lines += [
        f"| arm | seeds | {short} per 1,000, per seed | mean (95 %) | {short} per CPU-hour, mean (95 %) | distinct {short} modes "
        "| coverage | "
        + "".join(f"{k} per 1,000 | " for k in others)
        + "default / arm per 1,000 (95 %) | p | Cliff's delta | default / arm per CPU-hour (95 %) | p |",
        "|---" * (12 + len(others)) + "|",
    ]
    import numpy as np

    for r in res["comparison"]:
        a, h = arms[r["arm"]], hour.get(r["arm"])
        per = ", ".join(f"{v:.1f}" for v in r["counts"])
        vs = (
            "| - | - | - | - | - |"
            if r["p"] is None
            else f"| {_f(r['ratio'], 2)} ({_f(r['ratio_lo'], 2)}-{_f(r['ratio_hi'], 2)}) | {r['p']:.4f} | {r['effect']:+.2f} "
            + (
                f"| {_f(h['ratio'], 2)} ({_f(h['ratio_lo'], 2)}-{_f(h['ratio_hi'], 2)}) | {h['p']:.4f} |"
                if h
                else "| | |"
            )
        )
        lines.append(
            f"| {r['arm']} | {r['seeds']} | {per} | {r['mean']:.1f} ({r['lo']:.1f}-{r['hi']:.1f}) | "
            + (f"{h['mean']:.1f} ({h['lo']:.1f}-{h['hi']:.1f})" if h else "")
            + f" | {a['distinct_modes']} | {100 * a['coverage']:.0f} % | "
            + "".join(f"{np.mean(list(a[k].values())):.1f} | " for k in others)
            + vs[2:]
        )
    ref, ref_h = next(r for r in res["comparison"] if r["arm"] == t["ratio_over"]), hour.get(t["ratio_over"])
    modes = arms["default"]["distinct_modes"]
    lines += [
        "",
        f"Per seed: the first {p['budget']} scenarios of each campaign; intervals: bootstrap over the seeds "
        "(10,000 resamples, seed 0); p: two-sided Mann-Whitney U of the default's seeds against the arm's, "
        "exact with ties (a permutation test over every split of the seeds, asg_analysis.stats); "
        "Cliff's delta > 0: the default's seeds rank higher.",
        "",
        f"**Target ({t['ratio']:g}x {t['ratio_over']} per 1,000"
        + (f" and {t.get('ratio_per_cpu_hour', t['ratio']):g}x per CPU-hour" if t.get("per_cpu_hour") else "")
        + (f", p < {t['p']:g}" if t.get("p") is not None else ", descriptive: no test")
        + (f", >= {t['distinct_modes']} distinct {short} modes" if t.get("distinct_modes") else "")
        + "): "
        + ("met" if res["target_met"] else "missed")
        + f".** The default against {t['ratio_over']}: {_x(ref['ratio'])} per 1,000 "
        f"({_f(ref['ratio_lo'], 2)}-{_f(ref['ratio_hi'], 2)}, p = {ref['p']:.4f})"
        + (
            f", {_x(ref_h['ratio'])} per CPU-hour ({_f(ref_h['ratio_lo'], 2)}-{_f(ref_h['ratio_hi'], 2)}, "
            f"p = {ref_h['p']:.4f})"
            if ref_h
            else ""
        )
        + f"; {modes} distinct {short} modes over its seeds.",
    ]
    answer = _plain_answer(t, ref, ref_h, plural)
    lines += ["", f"**{question(p)} {answer[0].upper() + answer[1:]}.**"]
    w = res.get("winner")
    if w:
        lines += [
            "",
            f"**Winner (most {plural} per CPU-hour, mean over the seeds): {w['arm']}, "
            f"{w['per_cpu_hour']:.1f} per CPU-hour.** " + _who_runs(w["train_args"]),
        ]
    if figure:
        lines += ["", f"![{plural} by failure mode, per arm (the coverage map)]({figure})"]
    if budget:  # the why: how each arm spends its budget (asg_analysis.budget)
        lines += ["", "How each arm spends its budget (`python3 -m asg_analysis budget`):", "", budget]
    if budget_figure:
        lines += [
            "",
            f"![{plural} as each arm goes, and how close to the route it puts obstacles]({budget_figure})",
        ]
    lines.append(markers(p)[3])
    return "\n".join(lines)


def coverage_figure(res: dict, out: str) -> None:
    """The coverage map: for each arm, its flaw findings over all its seeds in the cells of the
    failure-mode feature map (rows: obstacle hit, with or without a shadow ahead; columns: quarter
    of the route and side), darker for more; an empty cell is a mode the arm never found."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from asg_agent.records import failure_modes as fm

    meshes = sorted({m for a in res["arms"].values() for m in a["meshes"]})
    rows = [(o, s) for o in meshes + ["none"] for s in ("shadow", "lit")]
    cols = [(q, side) for q in range(fm.ROUTE_BINS) for side in fm.SIDES + ("none",)]
    arms = list(res["arms"])
    fig, axes = plt.subplots(1, len(arms), figsize=(3.2 * len(arms), 0.32 * len(rows) + 1.6), squeeze=False)
    top = max((n for a in res["arms"].values() for n in a["mode_counts"].values()), default=1)
    for ax, arm in zip(axes[0], arms):
        grid = np.zeros((len(rows), len(cols)))
        for key, n in res["arms"][arm]["mode_counts"].items():
            o, q, side, s = key.split("|")
            if (o, s) in rows and (int(q), side) in cols:
                grid[rows.index((o, s)), cols.index((int(q), side))] += n
        ax.imshow(np.ma.masked_equal(grid, 0), cmap="viridis_r", vmin=0, vmax=top, aspect="auto")
        ax.set_title(f"{arm}\n{int(grid.sum())} flaw, {int((grid > 0).sum())} modes", fontsize=9)
        ax.set_xticks(range(len(cols)))
        ax.set_xticklabels([f"Q{q + 1} {side[0]}" for q, side in cols], rotation=90, fontsize=6)
        ax.set_yticks(range(len(rows)))
        ax.set_yticklabels(
            [f"{o} {'sh' if s == 'shadow' else 'lit'}" for o, s in rows] if ax is axes[0][0] else [], fontsize=6
        )
        ax.set_xticks(np.arange(-0.5, len(cols)), minor=True)
        ax.set_yticks(np.arange(-0.5, len(rows)), minor=True)
        ax.grid(which="minor", color="#dddddd", linewidth=0.4)
    fig.suptitle(
        "Flaw findings by failure mode over all seeds (rows: obstacle hit, shadow ahead or lit; columns: route "
        "quarter, side l/o/r/n); darker: more, blank: none",
        fontsize=9,
    )
    fig.tight_layout()
    fig.savefig(out, dpi=130)
    plt.close(fig)


def status_markdown(st: dict, study: str = "flaw", cls: str = "flaw") -> str:
    """The status block: a row a campaign, the endpoint's class (counted under `flaw`) and the
    attribution's other classes (other_classes) beside it."""
    others = next((c["others"] for c in st.values() if c.get("others")), ["model", "stack"])
    lines = [
        markers({"name": study})[0],
        f"| campaign | arm | seed | scenarios | {cls} per 1,000 (95 % exact) | {cls} | "
        + "".join(f"{k} | " for k in others)
        + f"distinct {cls} modes | CPU-hours | {cls} per CPU-hour | CPU | deviations |",
        "|---" * (11 + len(others)) + "|",
    ]
    for name, c in st.items():
        if not c["scenarios"]:
            lines.append(f"| {name} | {c['arm']} | {c['seed']} | 0 of {c['budget']} |" + " |" * (7 + len(others)))
            continue
        done = c["scenarios"] >= c["budget"]
        lo, hi = c["flaw_interval"]
        per_h = "" if c["flaw_per_cpu_hour"] is None else f"{c['flaw_per_cpu_hour']:.1f}"
        lines.append(
            f"| {name} | {c['arm']} | {c['seed']} | {c['scenarios']}{'' if done else ' of ' + str(c['budget'])} | "
            f"{c['flaw_per_1000']:.1f} ({lo:.1f}-{hi:.1f}) | {c['flaw']} | "
            + "".join(f"{c[k]} | " for k in others)
            + f"{c['modes']} | {c['cpu_hours']:.2f}{'' if c.get('cpu_measured') else ' †'} | {per_h} | {c['cpu']} | {'; '.join(c['deviations']) or 'none'} |"
        )
    done = sum(c["scenarios"] >= c["budget"] for c in st.values())
    lines += ["", f"{done} of {len(st)} campaigns complete."]
    if any(c["scenarios"] and not c.get("cpu_measured") for c in st.values()):
        lines += [
            "",
            "† CPU-hours by the clock (wall time x cores, protocol.wall_cpu_hours): a campaign run before "
            "the protocol's amendment 1, or with a run the plan did not measure; the others count the "
            "CPU time measured (protocol.measured_cpu_hours).",
        ]
    lines.append(markers({"name": study})[1])
    return "\n".join(lines)
