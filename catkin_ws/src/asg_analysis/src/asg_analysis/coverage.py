"""Coverage of a failure atlas (issue #93; no ROS): protocol v5's endpoint read from exports.

    python3 -m asg_analysis coverage doc [--check]                 # docs/agent.md's atlas block
    python3 -m asg_analysis coverage record [--check]              # the v5 record's blocks
    python3 -m asg_analysis coverage figure [--out docs/images/atlas_growth.png]
    python3 -m asg_analysis coverage arms ATLAS ARM=GLOB [ARM=GLOB ...] [--budget 300] [--radius 5]

`arms` gives, per arm, each seed's recall of the atlas within its first BUDGET scenarios (the
share of the atlas's places a flaw finding of the same class came within the radius of), per
class, the new places beyond the atlas, the scenarios to half the atlas and distinct findings at
2 m and 5 m; then each arm against the first (the baseline): the ratio of mean recalls with its bootstrap
interval and the exact two-sided Mann-Whitney test (stats.mann_whitney, ties included). The
atlas file and its places are scoring/atlas.py's; the recall of one export is the `atlas recall`
command's (asg_agent.cli.atlas.recall_of).
"""

import argparse
import functools
import glob
import os
import sys
from typing import Dict, List

from asg_agent.cli.atlas import recall_of, summary_lines
from asg_agent.paths import REPO
from asg_agent.records import atlas as ra
from asg_agent.records.export import read_export
from asg_agent.scoring import atlas as sa
from asg_agent.scoring.places import count_distinct, place_of_row
from asg_analysis import stats

PROG = "python3 -m asg_analysis coverage"

DOC = os.path.join(REPO, "docs", "agent.md")
BEGIN, END = "<!-- atlases: begin -->", "<!-- atlases: end -->"
FIGURE = os.path.join(REPO, "docs", "images", "atlas_growth.png")


def atlas_files() -> List[str]:
    return sorted(glob.glob(os.path.join(REPO, "results", "atlas", "*.json")))


def doc_block(paths: List[str]) -> str:
    """The block of docs/agent.md: each atlas's `show` lines under its file name."""
    out = [BEGIN, "```text"]
    for p in paths:
        out.append(f"$ rosrun asg_agent atlas show {os.path.relpath(p, REPO)}")
        out += summary_lines(ra.read(p))
    return "\n".join(out + ["```", END])


def rewrite(doc: str, blocks: Dict[str, str], check: bool) -> int:
    """Replaces each block NAME of `doc` by its text (markers included; docblocks writes it); with
    `check`, exit 1 when one is stale, 2 when the page lacks one."""
    from asg_analysis.docblocks import markers, rewrite_between

    return max(rewrite_between(doc, *markers(name), body, check, "coverage") for name, body in blocks.items())


def rewrite_doc(check: bool) -> int:
    """docs/agent.md's atlas block and the README's answer."""
    a = rewrite(DOC, {"atlases": doc_block(atlas_files())}, check)
    begin, end = "<!-- answer: begin -->", "<!-- answer: end -->"
    return max(a, rewrite(README, {"answer": f"{begin}\n{readme_answer()}\n{end}"}, check))


RECORD = os.path.join(REPO, "docs", "studies", "2026-12-06-coverage-v5.md")
V1 = os.path.join(REPO, "results", "coverage_v5", "exp1-flaw.v1.json")
# the atlas the pilot was read against and chosen by (v2, kept as it was); the current one is results/atlas/
V2 = os.path.join(REPO, "results", "coverage_v5", "exp1-flaw.v2.json")
CURRENT = os.path.join(REPO, "results", "atlas", "exp1-flaw.json")


def _block(name: str, lines: str) -> str:
    return f"<!-- {name}: begin -->\n```text\n{lines}\n```\n<!-- {name}: end -->"


def fringe(path: str, radius: float = sa.RADIUS_M) -> str:
    """How many of an atlas's places seen by one finding lie within twice the radius of another
    place of their class (the fringe of a region found often), and how many findings those
    neighbours hold."""
    import math

    g = next(g for g in ra.read(path)["groupings"] if g["radius_m"] == radius)["places"]
    single = [p for p in g if p["findings"] == 1]
    near = []
    for p in single:
        nb = [
            q
            for q in g
            if q is not p and q["cls"] == p["cls"] and math.hypot(p["x"] - q["x"], p["y"] - q["y"]) < 2 * radius
        ]
        if nb:
            near.append(max(q["findings"] for q in nb))
    return (
        f"{os.path.relpath(path, REPO)}: {len(near)} of its {len(single)} places seen by one finding lie within "
        f"{2 * radius:g} m of another place of their class; the largest neighbour of each holds "
        f"{sorted(near)} findings"
    )


@functools.lru_cache(maxsize=1)
def record_blocks() -> Dict[str, str]:
    """The v5 record's generated blocks: v4's arms read against atlas v1 (the protocol's baseline),
    the pilot's arms against atlas v2 (the one it was chosen by) beside v4's route-random and random,
    and v4's arms against the current atlas (what the README's answer reads)."""
    v4 = os.path.join(REPO, "results", "distinct_v4")
    base = {
        "route-random": sorted(glob.glob(os.path.join(v4, "dist4-route-random-s3?.jsonl.gz"))),
        "v4 default (novelty-ts)": sorted(glob.glob(os.path.join(v4, "dist4-default-s3?.jsonl.gz"))),
        "random, route-wide": sorted(glob.glob(os.path.join(v4, "dist4-random-own-s3?.jsonl.gz"))),
    }
    out = {"v4 baseline": _block("v4 baseline", arms_text(arms(V1, base, 300)))}
    out["fringe"] = _block("fringe", fringe(V2))
    pilot = os.path.join(REPO, "results", "coverage_v5")
    specs = dict(base)
    for arm in ("cov-wide", "cov-abs", "cov-filter", "cov-mutate", "cov-veto"):
        found = sorted(glob.glob(os.path.join(pilot, f"cov5-pilot-{arm}-s*.jsonl.gz")))
        if found:
            specs[f"pilot {arm}"] = found
    t = arms(V2, specs, 300)
    out["pilot"] = _block("pilot", arms_text(t))
    out["rates"] = _block("rates", rates_text(t))
    out["current atlas"] = _block("current atlas", arms_text(arms(CURRENT, base, 300)))
    out["current fringe"] = _block("current fringe", fringe(CURRENT))
    return out


def rates_text(t: Dict) -> str:
    """Each arm's flaw findings in its first scenarios, pooled over its seeds: how often it finds
    the flaw at all, beside how many distinct places it covers."""
    lines = []
    for arm, rows in t["arms"].items():
        k, n = sum(r["findings"] for r in rows), sum(r["scenarios"] for r in rows)
        d5 = sum(r["distinct_5m"] for r in rows)
        lines.append(
            f"{arm}: {k} flaw findings in {n:,} scenarios (1 in {n / k:.1f}), {d5} distinct at 5 m "
            f"({d5 / k:.2f} of them)"
        )
    return "\n".join(lines)


README = os.path.join(REPO, "README.md")


def verdict(test: Dict, alpha: float = 0.05) -> str:
    """What a comparison shows, never stronger than its test: better or worse only where the exact
    test is below `alpha` and the ratio's interval excludes 1."""
    if test["p"] < alpha and test["lo"] > 1.0:
        return "Yes"
    if test["p"] < alpha and test["hi"] < 1.0:
        return "No: it shows fewer"
    lean = "more" if test["ratio"] > 1.0 else "fewer"
    return f"Not shown (on average {lean}, within chance at this number of seeds)"


def readme_answer() -> str:
    """The README's answer to whether the default search is worth its cost: the default's recall
    of Exp. 1's atlas against route-random's, per seed, with the ratio's interval and the exact
    test (the record's baseline arms, read against the current atlas)."""
    from asg_agent.defaults import DEFAULTS

    v4 = os.path.join(REPO, "results", "distinct_v4")
    specs = {
        "route-random": sorted(glob.glob(os.path.join(v4, "dist4-route-random-s3?.jsonl.gz"))),
        "default": sorted(glob.glob(os.path.join(v4, "dist4-default-s3?.jsonl.gz"))),
    }
    t = arms(CURRENT, specs, 300)
    mean = {a: sum(r["recall"] for r in rows) / len(rows) for a, rows in t["arms"].items()}
    per = {a: ", ".join(f"{r['recall']:.2f}" for r in rows) for a, rows in t["arms"].items()}
    s = t["tests"]["default"]
    n = len(t["arms"]["default"])
    return (
        f"**Does the search find more than sampling?** {verdict(s)}. On the paper's Exp. 1 with the flawed "
        f"U-Net, counted as the share of the scene's {t['places']} known failure places (its [failure "
        f"atlas](docs/agent.md#failure-atlas-and-coverage)) that a campaign shows within {t['budget']} "
        f"scenarios, the default search (`{DEFAULTS['method'].value}`) covered {mean['default']:.2f} (per seed "
        f"{per['default']}) and route-random, random layouts near the route and the cheapest competitor, "
        f"{mean['route-random']:.2f} ({per['route-random']}): {s['ratio']:.2f}x (95 % interval "
        f"{s['lo']:.2f}-{s['hi']:.2f}), {n} seeds a side, the verdict by the exact Mann-Whitney test at 0.05 "
        f"([the study](docs/studies/2026-12-06-coverage-v5.md), generated by `python3 -m asg_analysis coverage doc`)."
    )


def figure(out: str) -> str:
    """Each atlas's growth curve at 5 m (places covered along a seeded shuffle of its pooled
    scenarios) beside its Chao1 and Chao2 estimates."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paths = atlas_files()
    fig, axes = plt.subplots(1, len(paths), figsize=(3.2 * len(paths), 3.0), squeeze=False)
    for ax, p in zip(axes[0], paths):
        d = ra.read(p)
        g = next(g for g in d["groupings"] if g["radius_m"] == sa.RADIUS_M)
        n, k = zip(*g["growth"])
        ax.plot(n, k, color="tab:blue", label="places covered")
        ax.axhline(g["chao1"]["chao1"], color="tab:red", ls="--", label="Chao1 (findings)")
        ax.axhline(g["chao2"]["chao2"], color="tab:green", ls=":", label="Chao2 (campaigns)")
        i = d["identity"]
        ax.set_title(
            f"{os.path.basename(p)[:-5]} v{d['version']}, {i['kind']}\ncompleteness {g['chao1']['completeness']:.2f} "
            f"(Chao1), {g['chao2']['completeness']:.2f} (Chao2)",
            fontsize=8,
        )
        ax.set_xlabel("scenarios pooled (shuffled)", fontsize=8)
        ax.tick_params(labelsize=7)
    axes[0][0].set_ylabel(f"places at {sa.RADIUS_M:g} m", fontsize=8)
    axes[0][0].legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def campaign_row(atlas: sa.Atlas, path: str, budget: int) -> Dict:
    """One export's endpoint figures within `budget` scenarios."""
    campaign, rows = read_export(path)
    diff = sa.same_identity(atlas.identity, ra.identity(campaign, atlas.identity["kind"]))
    if diff:
        raise ValueError(f"{path}: another identity than the atlas's ({', '.join(diff)})")
    rows = sorted(rows, key=lambda r: r["job"])[:budget]
    r = recall_of(atlas, rows, budget)
    found = [place_of_row(x) for x in rows if sa.is_finding(x, atlas.identity["kind"])]
    from asg_analysis.endpoints import cpu_hours

    hours = cpu_hours(campaign)
    return dict(
        r,
        cpu_hours=hours,
        recall_per_cpu_hour=r["recall"] / hours if hours else None,
        campaign=campaign["name"],
        seed=campaign["seed"],
        findings=len(found),
        distinct_2m=count_distinct(found, 2.0),
        distinct_5m=count_distinct(found, 5.0),
    )


def arms(atlas_path: str, specs: Dict[str, List[str]], budget: int, radius: float = sa.RADIUS_M) -> Dict:
    """Every arm's per-seed rows and each arm against the first (see the module's text)."""
    atlas = sa.load(atlas_path, radius)
    out = {"atlas": os.path.relpath(atlas_path, REPO), "budget": budget, "places": len(atlas), "arms": {}}
    for arm, paths in specs.items():
        out["arms"][arm] = [campaign_row(atlas, p, budget) for p in paths]
    first = next(iter(specs))
    ref = [r["recall"] for r in out["arms"][first]]
    out["tests"] = {}
    for arm in list(specs)[1:]:
        mine = [r["recall"] for r in out["arms"][arm]]
        ratio, lo, hi = stats.ratio_ci(mine, ref)
        out["tests"][arm] = dict(stats.mann_whitney(mine, ref), ratio=ratio, lo=lo, hi=hi)
    return out


def arms_text(t: Dict) -> str:
    lines = [f"recall of {t['atlas']} ({t['places']} places at the radius) within {t['budget']} scenarios"]
    for arm, rows in t["arms"].items():
        per = ", ".join(f"{r['recall']:.2f}" for r in rows)
        mean = sum(r["recall"] for r in rows) / len(rows)
        lines.append(
            f"  {arm}: {mean:.3f} (per seed {per}); new places {[r['new'] for r in rows]}; "
            f"distinct at 5 m {[r['distinct_5m'] for r in rows]}; half the atlas after {[r['half_at'] for r in rows]}"
        )
        for cls in sorted(rows[0]["by_class"]):
            a = sum(r["by_class"][cls][0] for r in rows) / len(rows)
            lines.append(f"    {cls}: {a:.1f} of {rows[0]['by_class'][cls][1]} covered on average")
    first = next(iter(t["arms"]))
    for arm, s in t["tests"].items():
        lines.append(
            f"  {arm} / {first}: {s['ratio']:.2f}x ({s['lo']:.2f}-{s['hi']:.2f}), exact Mann-Whitney p = {s['p']:.3f}"
        )
    return "\n".join(lines)


def run(argv=None) -> int:
    import json

    p = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    d = sub.add_parser("doc", help="rewrite docs/agent.md's atlas block from results/atlas/")
    d.add_argument("--check", action="store_true", help="exit 1 when the block is stale")
    rc = sub.add_parser("record", help="rewrite the v5 record's blocks from the exports")
    rc.add_argument("--check", action="store_true", help="exit 1 when a block is stale")
    f = sub.add_parser("figure", help="the atlases' growth curves")
    f.add_argument("--out", default=FIGURE)
    a = sub.add_parser("arms", help="protocol v5's endpoint per arm and seed, each arm against the first")
    a.add_argument("atlas")
    a.add_argument("arms", nargs="+", help="ARM=GLOB of its exports")
    a.add_argument("--budget", type=int, default=300)
    a.add_argument("--radius", type=float, default=sa.RADIUS_M)
    a.add_argument("--json", default="", help="also write the figures to this JSON file")
    args = p.parse_args(argv)
    try:
        if args.cmd == "doc":
            return rewrite_doc(args.check)
        if args.cmd == "record":
            return rewrite(RECORD, record_blocks(), args.check)
        if args.cmd == "figure":
            print(figure(args.out))
            return 0
        specs = {}
        for spec in args.arms:
            arm, eq, pattern = spec.partition("=")
            paths = sorted(glob.glob(pattern))
            if not eq or not paths:
                raise ValueError(f"arm {spec!r}: must be ARM=GLOB matching exports")
            specs[arm] = paths
        t = arms(args.atlas, specs, args.budget, args.radius)
    except ValueError as e:
        print(f"coverage: {e}", file=sys.stderr)
        return 2
    print(arms_text(t))
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump(t, fh, indent=1, sort_keys=True)
    return 0
