"""What gap_nav's search adds, and what its failures are (issue #68 item 11; no ROS).

gap_nav's study (results/gap_nav/plan.txt) compares MAP-Elites in the route space
(experiments/exp1-gap-nav-route.yaml: every obstacle within 10 m of the straight start-goal
segment) with uniform random over the whole landscape (experiments/exp1-gap-nav.yaml): two action
spaces as well as a search against none. MAP-Elites' first `init_random` jobs a seed are uniform
in its action space, chosen by no search (`MapElites.propose`); `make_method` sets init_random to
max(1, min(100, budget // 10)), 35 for a 350-scenario campaign, and the export's settings record
it (method_config.init_random; a disagreement is an error). From the committed exports:

- **the split**: failures per 1,000 of uniform random, of MAP-Elites' warm-up (its first
  init_random jobs a seed) and of its searched scenarios (the rest), each pooled over the seeds
  with an exact 95 % interval; the page's ratio (the whole arm against uniform random) split into
  *where obstacles may stand* (warm-up / uniform random) and *the search* (searched / warm-up;
  also the whole arm / warm-up, the factor that multiplies to the page's ratio); Fisher's exact
  test of each pair of pooled counts;
- **modes**: each seed's failure layouts grouped by single linkage, two layouts linked when every
  obstacle of one stands within `radius` [m] of the same obstacle (the same slot of the
  scenario, so the same class) of the other, at 2.5, 5 and 10 m: the number of groups, the
  largest's size; for the 5 m grouping the two largest groups' sizes, the largest's span (the
  largest distance by which one obstacle differs between two of its layouts: single linkage
  chains), how many of the scenario's obstacles its failures strike, and how many of them strike
  the most struck one; and the
  failures whose struck obstacle stands less than 25 m along the route from the start (its
  projection on the start-goal line), for the whole arm, its warm-up and uniform random;
- **reruns**: from the committed run-to-run spread (results/gap_nav/spread.json, asg_analysis.
  run_spread: the 20 scenarios of largest proxy of seed 0, 5 times each), how many of the 5
  repetitions each stored failure failed again: median, in 2 or fewer, in all, in none.

    python3 -m asg_analysis gap-nav-study                    # the markdown block
    python3 -m asg_analysis gap-nav-study --json results/gap_nav/study.json --doc docs/your-stack.md
    python3 -m asg_analysis gap-nav-study --doc docs/your-stack.md --check   # exit 1 when stale

- **route-random** (results/gap_nav/plan-route-random.txt, when its exports are in): every
  obstacle uniform within 10 m of the route, chosen by nothing, over the whole budget; the search's
  part measured directly: the whole arm and its searched scenarios against it, each with Fisher's
  exact test of the pooled counts (the plan's primary test: the whole arm against route-random).
"""

import argparse
import json
import os
import statistics
import sys
from typing import Dict, List, Sequence

import numpy as np
import yaml

from asg_agent.paths import REPO
from asg_agent.records.export import read_export
from asg_agent.scoring.attribution import RunOutcome
from asg_analysis.files import write_json
from asg_analysis.stats import exact_interval

PROG = "python3 -m asg_analysis gap-nav-study"

FOLDER = os.path.join(REPO, "results", "gap_nav")
SEEDS = (0, 1, 2)
SEARCH = [f"exp1-gap-nav-route-map-elites-s{k}" for k in SEEDS]
RANDOM = [f"exp1-gap-nav-random-s{k}" for k in SEEDS]
ROUTE_RANDOM = [f"exp1-gap-nav-route-random-s{k}" for k in SEEDS]
SPREAD = os.path.join(FOLDER, "spread.json")
RADII = (2.5, 5.0, 10.0)  # [m] the grouping's radii; MODE_RADIUS is the one described in full
MODE_RADIUS = 5.0
FIRST_M = 25.0  # [m] "the first 25 m of the route"
BEGIN = "<!-- gap_nav what the search adds -->"
END = "<!-- end gap_nav what the search adds -->"


def init_random(budget: int) -> int:
    """MAP-Elites' uniform warm-up for a campaign of `budget` scenarios (make_method's rule)."""
    return max(1, min(100, budget // 10))


def layout_groups(layouts, radius: float) -> List[List[int]]:
    """Single-linkage groups of layouts ((m, n, 2) positions [m], obstacle k of every layout the
    same slot): two layouts are linked when every obstacle of one stands within `radius` of the
    same obstacle of the other. The groups as lists of indices, largest first (ties: by their
    first index)."""
    p = np.asarray(layouts, dtype=np.float64)
    if p.ndim != 3 or p.shape[-1] != 2:
        raise ValueError(f"layouts must be (m, n, 2) positions, not {p.shape}")
    m = p.shape[0]
    if m == 0:
        return []
    apart = np.linalg.norm(p[:, None] - p[None], axis=-1).max(axis=-1)  # (m, m): the largest per-slot distance
    parent = list(range(m))

    def root(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for i, j in zip(*np.nonzero(np.triu(apart <= radius, 1))):
        parent[root(int(i))] = root(int(j))
    groups: Dict[int, List[int]] = {}
    for i in range(m):
        groups.setdefault(root(i), []).append(i)
    return sorted(groups.values(), key=lambda g: (-len(g), g[0]))


def span(layouts, group: Sequence[int]) -> float:
    """[m] the largest distance by which one obstacle differs between two layouts of `group`."""
    p = np.asarray(layouts, dtype=np.float64)[list(group)]
    return float(np.linalg.norm(p[:, None] - p[None], axis=-1).max()) if len(p) > 1 else 0.0


def route_of(head: dict):
    """(start, goal) [m] of a campaign's scenario, from the experiment text its export holds."""
    c = head["campaign"]
    exp = yaml.safe_load(c["experiment_text"])
    where = os.path.dirname(os.path.join(REPO, json.loads(c["settings"])["experiment_repo_file"]))
    with open(os.path.join(where, exp["scenario"]), encoding="utf-8") as f:
        op = yaml.safe_load(f)["operational"]
    return np.array([op["start_x"], op["start_y"]], float), np.array([op["goal_x"], op["goal_y"]], float)


def along(row: dict, start, goal) -> float:
    """[m] how far along the route from the start the obstacle a run struck stands."""
    u = (goal - start) / np.linalg.norm(goal - start)
    return float((np.asarray(row["positions"][row["collision_with"]], float) - start) @ u)


def read(folder: str, name: str):
    """(settings, scenario's start and goal, rows without ERROR runs) of a campaign's export."""
    import gzip

    with gzip.open(os.path.join(folder, f"{name}.jsonl.gz"), "rt", encoding="utf-8") as f:
        head = json.loads(f.readline())
    _, rows = read_export(os.path.join(folder, f"{name}.jsonl.gz"))
    return json.loads(head["campaign"]["settings"]), route_of(head), [r for r in rows if not RunOutcome.of(r).error]


def rate(failures: int, scenarios: int) -> Dict:
    lo, hi = exact_interval(failures, scenarios)
    return {
        "failures": failures,
        "scenarios": scenarios,
        "per_1000": 1000.0 * failures / scenarios,
        "per_1000_interval": [1000.0 * lo, 1000.0 * hi],
    }


def fisher(a: Dict, b: Dict) -> float:
    from scipy.stats import fisher_exact

    table = [[a["failures"], a["scenarios"] - a["failures"]], [b["failures"], b["scenarios"] - b["failures"]]]
    return float(fisher_exact(table, alternative="two-sided")[1])


def struck_early(rows, start, goal) -> int:
    return sum(r["collision_with"] is not None and along(r, start, goal) < FIRST_M for r in rows)


def warmup_rerun(folder: str, search: Sequence[str]):
    """MAP-Elites' warm-up scenarios run again on another machine (results/gap_nav/warmup-rerun/
    CAMPAIGN.jsonl, `rerun run ... --top 35 --select first`): per seed and pooled, the failures stored
    and again, the layouts that failed in one run and not the other, and Fisher's exact test of
    the two pooled counts and McNemar's exact test of the pairs; None until its files are in."""
    from scipy.stats import binomtest

    paths = [os.path.join(folder, "warmup-rerun", f"{name}.jsonl") for name in search]
    if not all(os.path.exists(p) for p in paths):
        return None
    seeds, stored_n, again_n, n, only_stored, only_again = {}, 0, 0, 0, 0, 0
    for name, path in zip(search, paths):
        settings, _, rows = read(folder, name)
        k = init_random(int(settings.get("total") or len(rows)))
        stored = {r["job"]: RunOutcome.of(r).fails for r in rows if r["job"] < k}
        with open(path, encoding="utf-8") as f:
            again = {r["job"]: RunOutcome.of(r) for r in map(json.loads, f)}
        if sorted(again) != sorted(stored) or any(o.error for o in again.values()):
            raise ValueError(f"{path}: not every warm-up job of {name} ran again without an error")
        a = {j: o.fails for j, o in again.items()}
        seeds[name] = {"scenarios": len(stored), "stored": sum(stored.values()), "again": sum(a.values())}
        stored_n, again_n, n = stored_n + sum(stored.values()), again_n + sum(a.values()), n + len(stored)
        only_stored += sum(stored[j] and not a[j] for j in stored)
        only_again += sum(a[j] and not stored[j] for j in stored)
    discordant = only_stored + only_again
    return {
        "seeds": seeds,
        "stored": rate(stored_n, n),
        "again": rate(again_n, n),
        "fisher_p": fisher(rate(stored_n, n), rate(again_n, n)),
        "only_stored": only_stored,
        "only_again": only_again,
        "mcnemar_p": float(binomtest(only_stored, discordant).pvalue) if discordant else 1.0,
    }


def reruns(path: str) -> Dict:
    """How many of the repetitions each stored failure of a run_spread file failed again."""
    with open(path, encoding="utf-8") as f:
        s = json.load(f)
    again = sorted(p["fails_again"] for p in s["per_scenario"] if p["stored"]["fails"])
    n = s["repetitions"]
    return {
        "campaign": s["campaign"],
        "scenarios": s["scenarios"],
        "repetitions": n,
        "stored_failures": len(again),
        "fails_again": again,
        "median": float(statistics.median(again)),
        "at_most_2": sum(k <= 2 for k in again),
        "every_time": sum(k == n for k in again),
        "never": sum(k == 0 for k in again),
        "reruns_failing": sum(again),
    }


def route_random_arm(folder: str, names: Sequence[str]):
    """route-random's pooled and per-seed rates and its failures struck early; None until every
    one of its exports is in."""
    if not names or not all(os.path.exists(os.path.join(folder, f"{n}.jsonl.gz")) for n in names):
        return None
    pooled, early, seeds = [0, 0], 0, {}
    for name in names:
        _, (start, goal), rows = read(folder, name)
        fails = [r for r in rows if RunOutcome.of(r).fails]
        pooled[0] += len(fails)
        pooled[1] += len(rows)
        early += struck_early(fails, start, goal)
        seeds[name] = rate(len(fails), len(rows))
    return {"campaigns": list(names), "pooled": rate(*pooled), "seeds": seeds, "struck_first_25m": early}


def comparisons(r_uniform: Dict, r_warm: Dict, r_searched: Dict, r_arm: Dict, route) -> tuple:
    """The ratios of the pooled rates and Fisher's exact tests between them; with route-random's
    arm (route_random_arm) the search against it too."""
    ratio = {
        "arm_over_uniform": r_arm["per_1000"] / r_uniform["per_1000"],
        "where_obstacles_may_stand": r_warm["per_1000"] / r_uniform["per_1000"],
        "search_over_warmup": r_searched["per_1000"] / r_warm["per_1000"],
        "arm_over_warmup": r_arm["per_1000"] / r_warm["per_1000"],
    }
    tests = {
        "warmup_vs_uniform": fisher(r_warm, r_uniform),
        "searched_vs_warmup": fisher(r_searched, r_warm),
    }
    if route:
        rr = route["pooled"]
        ratio.update(
            arm_over_route_random=r_arm["per_1000"] / rr["per_1000"],
            searched_over_route_random=r_searched["per_1000"] / rr["per_1000"],
            route_random_over_uniform=rr["per_1000"] / r_uniform["per_1000"],
        )
        tests.update(
            arm_vs_route_random=fisher(r_arm, rr),
            searched_vs_route_random=fisher(r_searched, rr),
            route_random_vs_warmup=fisher(rr, r_warm),
        )
    return ratio, tests


def study(
    folder: str = FOLDER,
    search: Sequence[str] = SEARCH,
    random: Sequence[str] = RANDOM,
    spread=SPREAD,
    route_random: Sequence[str] = ROUTE_RANDOM,
) -> Dict:
    seeds, warm, searched, early_warm = {}, [0, 0], [0, 0], 0
    for name in search:
        settings, (start, goal), rows = read(folder, name)
        k = init_random(int(settings.get("total") or len(rows)))
        recorded = settings.get("method_config", {}).get("init_random")
        if recorded is not None and recorded != k:
            raise ValueError(f"{name}: init_random {recorded} recorded, make_method's rule gives {k}")
        fails = [r for r in rows if RunOutcome.of(r).fails]
        w = [r for r in rows if r["job"] < k]
        wf = [r for r in w if RunOutcome.of(r).fails]
        layouts = [r["positions"] for r in fails]
        groups = {f"{radius:g}": layout_groups(layouts, radius) for radius in RADII}
        mode_groups = groups[f"{MODE_RADIUS:g}"]
        top = mode_groups[0] if mode_groups else []
        hit: Dict[str, int] = {}
        for i in top:
            r = fails[i]
            key = f"{r['meshes'][r['collision_with']]} {r['collision_with']}"
            hit[key] = hit.get(key, 0) + 1
        most = max(sorted(hit), key=hit.get) if hit else None
        seeds[name] = {
            "init_random": k,
            "warmup": rate(len(wf), len(w)),
            "searched": rate(len(fails) - len(wf), len(rows) - len(w)),
            "failures": len(fails),
            "groups": {rad: {"groups": len(g), "largest": len(g[0]) if g else 0} for rad, g in groups.items()},
            "largest_group": {
                "size": len(top),
                "next_size": len(mode_groups[1]) if len(mode_groups) > 1 else 0,
                "span_m": span(layouts, top) if top else 0.0,
                "jobs": sorted(fails[i]["job"] for i in top),
                "struck": dict(sorted(hit.items())),
                "most_struck": most,
                "most_struck_failures": hit.get(most, 0),
            },
            "struck_first_25m": struck_early(fails, start, goal),
        }
        warm[0] += len(wf)
        warm[1] += len(w)
        searched[0] += len(fails) - len(wf)
        searched[1] += len(rows) - len(w)
        early_warm += struck_early(wf, start, goal)
    uniform, early_uniform = [0, 0], 0
    for name in random:
        _, (start, goal), rows = read(folder, name)
        fails = [r for r in rows if RunOutcome.of(r).fails]
        uniform[0] += len(fails)
        uniform[1] += len(rows)
        early_uniform += struck_early(fails, start, goal)
    r_uniform, r_warm, r_searched = rate(*uniform), rate(*warm), rate(*searched)
    r_arm = rate(warm[0] + searched[0], warm[1] + searched[1])
    failures = r_arm["failures"]
    route = route_random_arm(folder, route_random)
    ratio, tests = comparisons(r_uniform, r_warm, r_searched, r_arm, route)
    again = warmup_rerun(folder, search)
    if again and route:  # on one machine: the warm-up run again against route-random
        again["again_vs_route_random_p"] = fisher(again["again"], route["pooled"])
    return {
        "search": list(search),
        "random": list(random),
        "uniform": r_uniform,
        "warmup": r_warm,
        "searched": r_searched,
        "arm": r_arm,
        "route_random": route,
        "warmup_rerun": again,
        "ratio": ratio,
        "fisher_p": tests,
        "seeds": seeds,
        "mode_radius_m": MODE_RADIUS,
        "first_m": FIRST_M,
        "struck_first_25m": {
            "arm": sum(s["struck_first_25m"] for s in seeds.values()),
            "arm_failures": failures,
            "warmup": early_warm,
            "warmup_failures": r_warm["failures"],
            "uniform": early_uniform,
            "uniform_failures": r_uniform["failures"],
        },
        "reruns": reruns(spread) if spread else None,
    }


def _rate(r: Dict) -> str:
    lo, hi = r["per_1000_interval"]
    return f"{r['scenarios']:,} | {r['failures']} | {r['per_1000']:.1f} ({lo:.1f}-{hi:.1f})"


def markdown(s: Dict) -> str:
    k = sorted({v["init_random"] for v in s["seeds"].values()})
    k_txt = "/".join(map(str, k))
    n = sorted({v["warmup"]["scenarios"] + v["searched"]["scenarios"] for v in s["seeds"].values()})
    last = "/".join(str(v - 1) for v in n)
    q, p = s["ratio"], s["fisher_p"]
    out = [
        BEGIN,
        "<!-- generated by `python3 -m asg_analysis gap-nav-study --doc docs/your-stack.md`; do not edit -->",
        "| scenarios | obstacles stand | chosen by | scenarios | failures | per 1,000 (95 % exact interval) |",
        "|---|---|---|---|---|---|",
        f"| exp1-gap-nav-random, every job | anywhere on the landscape | nothing (uniform) | {_rate(s['uniform'])} |",
        f"| exp1-gap-nav-route-map-elites, jobs 0-{k[0] - 1} (its warm-up) | within 10 m of the route "
        f"| nothing (uniform) | {_rate(s['warmup'])} |",
        f"| exp1-gap-nav-route-map-elites, jobs {k_txt}-{last} | within 10 m of the route | the search "
        f"| {_rate(s['searched'])} |",
        f"| exp1-gap-nav-route-map-elites, every job | within 10 m of the route | both | {_rate(s['arm'])} |",
    ]
    route = s.get("route_random")
    if route:
        out.append(
            f"| exp1-gap-nav-route-random, every job | within 10 m of the route | nothing (uniform) "
            f"| {_rate(route['pooled'])} |"
        )
    out += [
        "",
        f"Pooled over seeds {', '.join(str(i) for i in SEEDS)}. The arm's {q['arm_over_uniform']:.1f}x uniform random's "
        f"rate is {q['where_obstacles_may_stand']:.1f}x (the warm-up against uniform random: where obstacles may "
        f"stand) times {q['arm_over_warmup']:.2f}x (the whole arm against its warm-up); the searched scenarios "
        f"alone fail {q['search_over_warmup']:.2f}x as often as the warm-up. Fisher's exact test: warm-up against "
        f"uniform random p = {p['warmup_vs_uniform']:.2g}, searched against warm-up p = {p['searched_vs_warmup']:.2g}.",
    ]
    if route:
        out.append(
            f"Against route-random (the same place for obstacles, chosen by nothing, every job): the whole arm "
            f"fails {q['arm_over_route_random']:.2f}x as often (Fisher's exact test p = {p['arm_vs_route_random']:.2g}, "
            f"the plan's primary test), its searched scenarios {q['searched_over_route_random']:.2f}x "
            f"(p = {p['searched_vs_route_random']:.2g}); route-random against the warm-up p = "
            f"{p['route_random_vs_warmup']:.2g}."
        )
    w = s.get("warmup_rerun")
    if w:
        a, b = w["stored"], w["again"]
        out.append(
            f"The warm-up's {a['scenarios']} scenarios run again on this project's AMX Xeon (`rerun run ... --top 35 "
            f"--select first`): {b['failures']} failures ({b['per_1000']:.1f} per 1,000) against {a['failures']} stored "
            f"({a['per_1000']:.1f}), Fisher's exact test p = {w['fisher_p']:.2g}; {w['only_stored']} layouts failed only "
            f"as stored and {w['only_again']} only again (McNemar's exact test p = {w['mcnemar_p']:.2g})"
            + (
                f"; against route-random, on the same machine, p = {w['again_vs_route_random_p']:.2g}."
                if "again_vs_route_random_p" in w
                else "."
            )
        )
    out += [
        "",
        "| campaign | failures | warm-up failures | layout groups at "
        + " / ".join(f"{r:g}" for r in RADII)
        + f" m: groups (largest) | largest {s['mode_radius_m']:g} m group: size (the next's), span, obstacles its "
        f"failures strike (the most struck one's failures) | struck an obstacle < {s['first_m']:g} m along the route |",
        "|---|---|---|---|---|---|",
    ]
    for name, v in s["seeds"].items():
        g = " / ".join(f"{x['groups']} ({x['largest']})" for x in v["groups"].values())
        t = v["largest_group"]
        out.append(
            f"| {name} | {v['failures']} | {v['warmup']['failures']} of {v['warmup']['scenarios']} | {g} "
            f"| {t['size']} ({t['next_size']}), {t['span_m']:.1f} m, {len(t['struck'])} ({t['most_struck_failures']}) "
            f"| {v['struck_first_25m']} |"
        )
    e = s["struck_first_25m"]
    out += [
        "",
        f"Struck an obstacle less than {s['first_m']:g} m along the route from the start: {e['arm']} of the "
        f"arm's {e['arm_failures']} failures, {e['warmup']} of its warm-up's {e['warmup_failures']}, {e['uniform']} "
        f"of uniform random's {e['uniform_failures']}"
        + (f", {route['struck_first_25m']} of route-random's {route['pooled']['failures']}." if route else "."),
    ]
    r = s["reruns"]
    if r:
        out += [
            "",
            f"Reruns ({r['campaign']}, its {r['scenarios']} scenarios of largest proxy, {r['repetitions']} times "
            f"each): its {r['stored_failures']} stored failures failed again in a median {r['median']:g} of "
            f"{r['repetitions']} repetitions; {r['at_most_2']} in 2 or fewer, {r['every_time']} in all "
            f"{r['repetitions']}, {r['never']} in none ({r['reruns_failing']} of "
            f"{r['repetitions'] * r['stored_failures']} reruns failed).",
        ]
    out.append(END)
    return "\n".join(out)


def run(argv=None) -> int:
    p = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    p.add_argument("--folder", default=FOLDER, help="the exports (NAME.jsonl.gz) and spread.json")
    p.add_argument("--json", default="", help="write the figures here (results/gap_nav/study.json)")
    p.add_argument("--doc", default="", help="rewrite the page's generated block (docs/your-stack.md)")
    p.add_argument("--check", action="store_true", help="with --doc: only say whether its block is stale (exit 1)")
    a = p.parse_args(argv)
    try:
        s = study(a.folder, spread=os.path.join(a.folder, "spread.json"))
    except (FileNotFoundError, ValueError) as e:
        print(f"gap_nav_study: {e}", file=sys.stderr)
        return 2
    block = markdown(s)
    if a.json and not a.check:
        write_json(a.json, s)
    if a.doc:
        from asg_analysis.docblocks import rewrite_between as rewrite_block

        rc = rewrite_block(a.doc, BEGIN, END, block, a.check, "gap_nav_study")
        if a.check:
            print("gap_nav_study: " + {0: "in step", 1: f"{a.doc}'s block is stale"}.get(rc, "no block"))
        return rc
    print(block)
    return 0
