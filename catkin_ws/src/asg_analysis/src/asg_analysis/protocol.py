"""A study fixed before its data (issue #37; no ROS): the protocol file names the experiment, the
arms, seeds and budget, the endpoint and the statistics; this module turns it into campaign plans
and reads the campaigns' exports back against it, printing every deviation.

    python3 -m asg_analysis.protocol plan experiments/protocol-round4.yaml pilot > results/round4/pilot.txt
    python3 -m asg_analysis.protocol choose experiments/protocol-round4.yaml results/round4
    python3 -m asg_analysis.protocol plan experiments/protocol-round4.yaml confirmatory \\
        --choice results/round4/pilot_choice.json > results/round4/plan.txt
    python3 -m asg_analysis.protocol analyse experiments/protocol-round4.yaml results/round4

Plans are lines of scripts/repro/campaigns.sh (NAME SCENARIOS LAUNCH ARGS...); campaigns are named
PROTOCOL-ARM-sSEED (pilot: PROTOCOL-pilot-reward-REWARD-sSEED, PROTOCOL-pilot-band-BAND-sSEED).
`choose` applies the pilot's stated rule to the pilot's exports and writes the choice; `analyse`
counts, per arm and seed, the endpoint class per 1,000 scenarios and the secondary scores, and
compares the default with every other arm (asg_analysis.stats).
"""

import argparse
import json
import os
import re
import sys
from typing import Dict, List, Optional

import yaml

from asg_agent.paths import REPO
from asg_agent.scoring import attribution as attr
from asg_agent.scoring import rewards as reward_registry

REQUIRED = ("name", "version", "experiment", "budget", "workers", "attribution", "endpoint", "pilot", "arms", "target")


#: from this protocol version on, the pilot's plan runs every arm's first seed before any arm's
#: second (early seeds inform early)
SEED_MAJOR_PILOT_VERSION = 3


#: the reference roles of each `attribution` a protocol may name (train.launch's attribution:=)
ATTRIBUTION_ROLES = {"three": attr.THREE_STACK, "release": (attr.RELEASE,)}


def _action_space(experiment: str) -> str:
    """The action space of an experiment file (a path relative to the repository)."""
    from asg_agent.records.experiment import load_experiment

    return load_experiment(os.path.join(REPO, experiment)).action_space


class ProtocolError(ValueError):
    pass


def load(path: str) -> dict:
    try:
        with open(path, encoding="utf-8") as f:
            p = yaml.safe_load(f)
    except (OSError, yaml.YAMLError) as e:
        raise ProtocolError(f"{path}: cannot read the protocol ({e})") from None
    missing = [k for k in REQUIRED if not isinstance(p, dict) or k not in p]
    if missing:
        raise ProtocolError(f"{path}: the protocol lacks {', '.join(missing)}")
    if p["endpoint"].get("class") not in attr.CLASSES:
        raise ProtocolError(f"{path}: endpoint class {p['endpoint'].get('class')!r} is not one of {attr.CLASSES}")
    if "default" not in p["arms"]:
        raise ProtocolError(f"{path}: no 'default' arm")
    for name, arm in p["arms"].items():
        if not arm.get("seeds") or not arm.get("method"):
            raise ProtocolError(f"{path}: arm {name!r} needs a method and seeds")
        overlap = set(arm["seeds"]) & set(p["pilot"]["seeds"])
        if overlap:
            raise ProtocolError(f"{path}: arm {name!r} reuses pilot seeds {sorted(overlap)}")
    p["_path"] = path
    return p


def _campaign(
    p: dict,
    name: str,
    method: str,
    seed: int,
    reward: str = "proxy",
    band: Optional[float] = None,
    experiment: str = "",
    budget: int = 0,
):
    experiment = experiment or p["experiment"]
    args = [
        f"method:={method}",
        f"seed:={seed}",
        f"experiment:={experiment}",
        f"workers:={p['workers']}",
        f"attribution:={p['attribution']}",
        f"reward:={reward}",
    ]
    if band is not None:
        args.append(f"route_band:={band:g}")
    if reward == "regret":  # every scenario re-run on the references
        args.append("candidates:=all")
    return {
        "name": name,
        "budget": budget or p["budget"],
        "method": method,
        "seed": seed,
        "reward": reward,
        "band": band,
        "experiment": experiment,
        "args": args,
    }


def campaigns(p: dict, stage: str, choice: Optional[dict] = None) -> List[dict]:
    """Every campaign of a stage ('pilot' or 'confirmatory'), each with its name and settings."""
    n = p["name"]
    out = []
    if stage == "pilot" and "search" in p["pilot"]:  # version 2: named search arms
        budget = p["pilot"].get("budget", p["budget"])
        for arm, a in p["pilot"]["search"].items():
            for s in p["pilot"]["seeds"]:
                c = _campaign(
                    p,
                    f"{n}-pilot-{arm}-s{s}",
                    a["method"],
                    s,
                    a.get("reward", "proxy"),
                    experiment=a.get("experiment", ""),
                    budget=budget,
                )
                out.append(dict(c, arm=arm))
        for band in p["pilot"].get("route_bands_m", []):
            for s in p["pilot"]["seeds"]:
                c = _campaign(p, f"{n}-pilot-band-{band:g}-s{s}", "route-random", s, band=float(band), budget=budget)
                out.append(dict(c, arm=f"band {band:g} m"))
        if p["version"] >= SEED_MAJOR_PILOT_VERSION:  # every arm's first seed before any arm's second
            seeds = list(p["pilot"]["seeds"])
            out.sort(key=lambda c: seeds.index(c["seed"]))
        return out
    if stage == "pilot":
        for reward in p["pilot"]["rewards"]:
            for s in p["pilot"]["seeds"]:
                out.append(
                    dict(
                        _campaign(p, f"{n}-pilot-reward-{reward}-s{s}", "td3-per-asp", s, reward),
                        arm=f"reward {reward}",
                    )
                )
        for band in p["pilot"]["route_bands_m"]:
            for s in p["pilot"]["seeds"]:
                out.append(
                    dict(
                        _campaign(p, f"{n}-pilot-band-{band:g}-s{s}", "route-random", s, band=float(band)),
                        arm=f"band {band:g} m",
                    )
                )
        return out
    if stage != "confirmatory":
        raise ProtocolError(f"stage {stage!r}: pilot or confirmatory")
    if choice is None:
        raise ProtocolError("the confirmatory plan needs the pilot's choice (protocol choose ...)")
    for arm, a in p["arms"].items():
        # "pilot": what the pilot chose (version 2 also chooses the search's method and experiment)
        method = choice["method"] if a["method"] == "pilot" else a["method"]
        reward = choice["reward"] if a.get("reward") == "pilot" else a.get("reward", "proxy")
        band = a.get("band_m")
        band = choice["band_m"] if band == "pilot" else band
        experiment = choice["experiment"] if a.get("experiment") == "pilot" else a.get("experiment", "")
        if a.get("experiment") == "pilot" and p.get("experiment_by_space"):
            # a study of another scene (issue #67's transfer): the chosen arm's action space there
            experiment = p["experiment_by_space"][_action_space(choice["experiment"])]
        for s in a["seeds"]:
            c = _campaign(p, f"{n}-{arm}-s{s}", method, s, reward, band, experiment=experiment)
            out.append(dict(c, arm=arm))
    return out


def plan_lines(cs: List[dict]) -> str:
    return "".join(f"{c['name']}  {c['budget']} train {' '.join(c['args'])}\n" for c in cs)


def per_seed(rows: List[dict], budget: int, cls: str) -> float:
    """Findings of class `cls` per 1,000 scenarios among the first `budget` jobs."""
    rows = [r for r in rows if r["job"] < budget]
    return 1000.0 * sum(r.get("attribution") == cls for r in rows) / max(1, len(rows))


def deviations(p: dict, c: dict, camp: dict, rows: List[dict]) -> List[str]:
    """What the export of campaign `c` does differently from the protocol (empty: nothing)."""
    out = []
    s = json.loads(camp["settings"]) if isinstance(camp.get("settings"), str) else camp.get("settings", {})
    jobs = {r["job"] for r in rows}
    budget = c.get("budget", p["budget"])
    if len(jobs & set(range(budget))) < budget:
        out.append(f"{c['name']}: {len(jobs & set(range(budget)))} of the {budget} scenarios")
    want = os.path.normpath(c.get("experiment") or p["experiment"])
    ran = s.get("experiment_repo_file") or s.get("experiment_file", "")
    if ran and not os.path.normpath(ran).endswith(want):
        out.append(f"{c['name']}: experiment {ran}, the protocol says {want}")
    for e in interruptions(s, rows):
        out.append(f"{c['name']}: {e}")
    if camp.get("adopted"):  # asg_analysis.reuse adopt: an older study's export, proven on today's code
        a = camp["adopted"]
        cpus = sorted({e["cpu"] for e in s.get("events", []) if e.get("cpu")})
        out.append(
            f"{c['name']}: adopted from {a['from']} (an older study's run"
            + (f", on {', '.join(cpus)}" if cpus else "")
            + f"; {a['proof']} repeats its first {a['budget']} jobs on today's code)"
        )
        for where in a.get("shared", []):  # what its own study's machine log said of it
            out.append(f"{c['name']}: shared the machine in its older study ({where})")
    if camp.get("method") != c["method"]:
        out.append(f"{c['name']}: method {camp.get('method')!r}, the protocol says {c['method']!r}")
    if camp.get("seed") != c["seed"]:
        out.append(f"{c['name']}: seed {camp.get('seed')}, the protocol says {c['seed']}")
    if s.get("reward", "proxy") != c["reward"]:
        out.append(f"{c['name']}: reward {s.get('reward')!r}, the protocol says {c['reward']!r}")
    refs = sorted((s.get("references") or {}).keys())
    want = sorted(ATTRIBUTION_ROLES.get(str(p["attribution"]), attr.THREE_STACK))
    if refs != want:
        out.append(f"{c['name']}: reference stacks {refs}, the protocol says {want}")
    if len(s.get("workers", [])) != p["workers"]:
        out.append(f"{c['name']}: {len(s.get('workers', []))} workers under test, the protocol says {p['workers']}")
    if c["band"] is not None and abs(float((s.get("method_config") or {}).get("band", -1)) - c["band"]) > 1e-9:
        out.append(f"{c['name']}: band {(s.get('method_config') or {}).get('band')}, the protocol says {c['band']}")
    if any(r.get("attribution") == attr.PENDING for r in rows):
        out.append(f"{c['name']}: candidates still pending attribution")
    return out


#: [s] a pause between two finished scenarios longer than this is an interruption (a stop, a
#: park) even where no event recorded it (campaigns before the events existed)
GAP_S = 600.0


def interruptions(settings: dict, rows: List[dict]) -> List[str]:
    """Every resume, restart and long pause of a campaign, in words: from the events its store
    recorded (Store.record_event) and from the gaps between its rows' finish times."""
    out = []
    for e in settings.get("events", []):
        if e.get("kind") in ("resume", "restart"):
            out.append(
                f"{e['kind']} after {e.get('stored', '?')} stored scenarios"
                + (f" on {e['cpu']}" if e.get("cpu") else "")
                + (f" at commit {e['commit'][:10]}" if e.get("commit") else "")
            )
    fin = sorted((r["finished"], r["job"]) for r in rows if r.get("finished"))
    for (t0, j0), (t1, _) in zip(fin, fin[1:]):
        if t1 - t0 > GAP_S:
            out.append(f"paused {t1 - t0:,.0f} s after job {j0}")
    return out


def cpu_hours(settings: dict, rows: List[dict], budget: int) -> float:
    """[h] what a campaign cost: its measured CPU time (measured_cpu_hours) where every run of it
    was measured, else wall_cpu_hours."""
    m = measured_cpu_hours(settings)
    return m if m is not None else wall_cpu_hours(settings, rows, budget)


def measured_cpu_hours(settings: dict) -> Optional[float]:
    """[h] the user + system CPU time of every run of the campaign (the plan's `cpu` events:
    cli.plan.cpu_event, the process tree of train.sh), or None when a run of it went unmeasured
    (a run outside a plan, or a campaign from before the protocol's amendment 1)."""
    events = settings.get("events", [])
    runs = sum(e.get("kind") in ("start", "resume", "restart") for e in events)
    cpu = [e for e in events if e.get("kind") == "cpu"]
    if not cpu or len(cpu) < runs:
        return None
    return sum(float(e["cpu_s"]) for e in cpu) / 3600.0


def wall_cpu_hours(settings: dict, rows: List[dict], budget: int) -> float:
    """[h] what the first `budget` scenarios of a campaign cost by the clock: the time from its
    start to the last of them finishing, less the pauses longer than GAP_S, times the machine's
    cores (each campaign of the project fills its machine: workers under test, references, the
    search). It grows with whatever else shares the machine: the fallback of cpu_hours."""
    fin = sorted(r["finished"] for r in rows if r.get("finished") and r["job"] < budget)
    if not fin:
        return 0.0
    events = settings.get("events", [])
    cores = next((e["cores"] for e in events if e.get("cores")), 2)
    start = next((e["time"] for e in events if e.get("kind") == "start"), fin[0] - rows_wall(rows))
    spans = [fin[0] - start] + [b - a for a, b in zip(fin, fin[1:])]
    return cores * sum(d for d in spans if d <= GAP_S) / 3600.0


def rows_wall(rows: List[dict]) -> float:
    """[s] the first finished row's own wall time (the start of a campaign without a start event)."""
    first = min((r for r in rows if r.get("finished")), key=lambda r: r["finished"], default=None)
    return float(first.get("wall_time", 0.0)) if first else 0.0


def read_arms(p: dict, folder: str, cs: List[dict]):
    """({arm: {seed: rows}}, {campaign name: campaign header}, deviations)."""
    from asg_agent.records.export import read_export

    arms: Dict[str, Dict[int, list]] = {}
    heads, devs = {}, []
    for c in cs:
        path = os.path.join(folder, c["name"] + ".jsonl.gz")
        if not os.path.isfile(path):
            devs.append(f"{c['name']}: no export ({path})")
            continue
        camp, rows = read_export(path)
        heads[c["name"]] = camp
        devs += deviations(p, c, camp, rows)
        arms.setdefault(c["arm"], {})[c["seed"]] = rows
    return arms, heads, devs


def choose(p: dict, folder: str) -> dict:
    """The pilot's choice by the protocol's rule: the reward and the band of largest mean endpoint
    findings per 1,000 over the pilot seeds (ties: more distinct modes, then list order)."""
    import numpy as np

    cs = campaigns(p, "pilot")
    arms, heads, devs = read_arms(p, folder, cs)
    cls = p["endpoint"]["class"]
    budget = p["pilot"].get("budget", p["budget"])

    from asg_agent.records import failure_modes as fm

    def score(arm):
        """(mean endpoint findings per 1,000 over the seeds, distinct failure modes of them)."""
        seeds = arms.get(arm, {})
        if not seeds:
            return (-1.0, -1)
        camp = heads[next(c["name"] for c in cs if c["arm"] == arm and c["seed"] in seeds)]
        modes = []
        for rows in seeds.values():
            keep = [r for r in rows if r["job"] < budget]
            modes += fm.modes_of(camp, keep, lambda r: r.get("attribution") == cls)
        return (float(np.mean([per_seed(r, budget, cls) for r in seeds.values()])), fm.distinct(modes))

    def per_hour(arm):
        """(mean endpoint findings per CPU-hour over the seeds, then score's figures)."""
        seeds = arms.get(arm, {})
        names = {c["seed"]: c["name"] for c in cs if c["arm"] == arm}
        vals = []
        for s_, rows in seeds.items():
            st = heads[names[s_]].get("settings") or "{}"
            h = cpu_hours(json.loads(st) if isinstance(st, str) else st, rows, budget)
            keep = [r for r in rows if r["job"] < budget]
            vals.append(sum(r.get("attribution") == cls for r in keep) / h if h else 0.0)
        return (float(np.mean(vals)) if vals else -1.0,) + score(arm)

    bands = [(score(f"band {b:g} m"), -k, b) for k, b in enumerate(p["pilot"].get("route_bands_m", []))]
    best_b = max(bands) if bands else None
    if "search" in p["pilot"]:  # version 2: the search arm (method, reward, experiment) and the band
        rule = per_hour if p["pilot"].get("choose_by") == "per_cpu_hour" else score  # version 3: per CPU-hour
        search = [(rule(arm), -k, arm) for k, arm in enumerate(p["pilot"]["search"])]
        best = max(search)[2]
        a = p["pilot"]["search"][best]
        return {
            "search": best,
            "method": a["method"],
            "reward": a.get("reward", "proxy"),
            "experiment": a.get("experiment") or p["experiment"],
            "band_m": float(best_b[2]) if best_b else None,
            "searches": {arm: sc[0] for sc, _, arm in search},
            "bands_m": {f"{b:g}": sc[0] for sc, _, b in bands},
            "deviations": devs,
            "protocol": p["_path"],
        }
    rewards = [(score(f"reward {r}"), -k, r) for k, r in enumerate(p["pilot"]["rewards"])]
    best_r = max(rewards)
    return {
        "reward": best_r[2],
        "band_m": float(best_b[2]),
        "rewards": {r: s[0] for s, _, r in rewards},
        "bands_m": {f"{b:g}": s[0] for s, _, b in bands},
        "deviations": devs,
        "protocol": p["_path"],
    }


def analyse(p: dict, folder: str, choice: dict) -> dict:
    from asg_agent.records import failure_modes as fm
    from asg_analysis import stats

    cs = campaigns(p, "confirmatory", choice)
    arms, heads, devs = read_arms(p, folder, cs)
    cls, budget = p["endpoint"]["class"], p["budget"]
    table = {}
    for arm, seeds in arms.items():
        camp = heads[next(c["name"] for c in cs if c["arm"] == arm and c["seed"] in seeds)]
        modes, meshes = [], []
        for rows in seeds.values():
            keep = [r for r in rows if r["job"] < budget]
            modes += fm.modes_of(camp, keep, lambda r: r.get("attribution") == cls)
            meshes = meshes or (keep[0]["meshes"] if keep else [])
        names = {c["seed"]: c["name"] for c in cs if c["arm"] == arm}
        hours = {}
        for s_, r in sorted(seeds.items()):
            st = heads[names[s_]].get("settings") or "{}"
            hours[s_] = cpu_hours(json.loads(st) if isinstance(st, str) else st, r, budget)
        done = sum(
            len({r["job"] for r in rows if r["job"] < budget}) >= budget
            and not any(r.get("attribution") == attr.PENDING for r in rows)
            for rows in seeds.values()
        )
        table[arm] = {
            "campaigns": len([c for c in cs if c["arm"] == arm]),
            "complete": done,
            "train_args": train_args(next(c for c in cs if c["arm"] == arm)["args"]),
            "mode_counts": {"|".join(map(str, m)): modes.count(m) for m in sorted(set(modes))},
            "meshes": sorted(set(meshes)),
            "per_cpu_hour": {
                s_: (
                    sum(x["job"] < budget and x.get("attribution") == cls for x in r) / hours[s_] if hours[s_] else None
                )
                for s_, r in sorted(seeds.items())
            },
            "cpu_hours": hours,
            "per_seed": {s: per_seed(r, budget, cls) for s, r in sorted(seeds.items())},
            **{k: {s: per_seed(r, budget, k) for s, r in sorted(seeds.items())} for k in other_classes(cls)},
            "distinct_modes": fm.distinct(modes),
            "coverage": fm.coverage(modes, meshes) if meshes else 0.0,
        }
    rows, rows_hour = [], []
    if "default" in table:
        rows = stats.compare({a: list(t["per_seed"].values()) for a, t in table.items()}, "default")
        if all(v is not None for t in table.values() for v in t["per_cpu_hour"].values()):
            rows_hour = stats.compare({a: list(t["per_cpu_hour"].values()) for a, t in table.items()}, "default")
    t = p["target"]
    ref = next((r for r in rows if r["arm"] == t["ratio_over"]), None)
    ref_hour = next((r for r in rows_hour if r["arm"] == t["ratio_over"]), None)
    met = None
    ratio_hour = t.get("ratio_per_cpu_hour", t["ratio"])  # version 3 sets its own per-CPU-hour ratio

    def significant(row):  # p: null in a protocol whose seeds cannot reach a test (descriptive)
        return t.get("p") is None or row["p"] < t["p"]

    if ref is not None and "default" in table:
        met = bool(
            ref["ratio"] >= t["ratio"]
            and significant(ref)
            and table["default"]["distinct_modes"] >= t["distinct_modes"]
            and (
                not t.get("per_cpu_hour")
                or (ref_hour is not None and ref_hour["ratio"] >= ratio_hour and significant(ref_hour))
            )
        )
    complete = sum(t["complete"] for t in table.values())
    winner = None
    if rows_hour and complete == len(cs) and any(r["mean"] > 0 for r in rows_hour):
        # the protocol's rule: most findings per CPU-hour, mean over the seeds (none when no arm found any)
        order = list(p["arms"])
        best = max(rows_hour, key=lambda r: (r["mean"], -order.index(r["arm"])))
        winner = {"arm": best["arm"], "per_cpu_hour": best["mean"], "train_args": table[best["arm"]]["train_args"]}
    return {
        "campaigns": len(cs),
        "complete": complete,
        "winner": winner,
        "arms": table,
        "comparison": rows,
        "comparison_per_cpu_hour": rows_hour,
        "target_met": met,
        "deviations": devs,
        "choice": choice,
    }


def train_args(args: List[str]) -> List[str]:
    """A campaign's launch arguments as `bash scripts/train.sh` takes them for the product's default:
    the generator (method, experiment, reward, band), without the study's seed, workers and
    attribution."""
    return [a for a in args if a.split(":=", 1)[0] not in ("seed", "workers", "attribution")]


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


#: the markers of round 5's study (protocol name "flaw")
BEGIN, END, RESULT_BEGIN, RESULT_END = markers({"name": "flaw"})


def _f(x: Optional[float], nd: int = 1) -> str:
    if x is None:
        return ""
    if x != x:  # nan: a ratio of two arms that found none
        return "undefined"
    return "inf" if x == float("inf") else f"{x:.{nd}f}"


def _x(ratio: float) -> str:
    """A ratio of means in prose: "1.60x", or "undefined" where neither arm found any."""
    return _f(ratio, 2) + ("" if ratio != ratio else "x")


def other_classes(cls: str):
    """The attribution's classes shown beside the endpoint's: model and stack findings beside flaw
    findings (three-stack attribution), shared failures beside regressions (a stack pair)."""
    return {"regression": ("shared",)}.get(cls, ("model", "stack"))


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
    if budget:  # the why: how each arm spends its budget (asg_analysis.studies.flaw_budget)
        lines += ["", "How each arm spends its budget (`asg_analysis.studies.flaw_budget`):", "", budget]
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


def status(p: dict, folder: str, choice_path: str = "") -> dict:
    """Every campaign of the protocol so far, each with its endpoint (first `budget` scenarios),
    cost and interruptions; nothing compared (that waits for complete stages). The confirmatory
    campaigns are those of the pilot's choice, `choice_path` (default FOLDER/pilot_choice.json);
    the endpoint's class is counted under the `flaw` keys, whatever the class (a stack pair's
    regressions), beside the other classes of the attribution."""
    from asg_agent.records import failure_modes as fm
    from asg_agent.records.export import read_export
    from asg_analysis.studies.stack_study import exact_interval

    cs = campaigns(p, "pilot")
    choice_path = choice_path or os.path.join(folder, "pilot_choice.json")
    if os.path.isfile(choice_path):
        with open(choice_path) as f:
            cs += campaigns(p, "confirmatory", json.load(f))
    out = {}
    shared = shared_machine(folder, [c["name"] for c in cs])
    for c in cs:
        path = os.path.join(folder, c["name"] + ".jsonl.gz")
        if not os.path.isfile(path):
            out[c["name"]] = {"arm": c["arm"], "seed": c["seed"], "budget": c["budget"], "scenarios": 0}
            continue
        camp, rows = read_export(path)
        settings = json.loads(camp["settings"]) if isinstance(camp.get("settings"), str) else camp["settings"]
        keep = [r for r in rows if r["job"] < c["budget"]]
        cls = p["endpoint"]["class"]
        others = other_classes(cls)
        count = {k: sum(r.get("attribution") == (cls if k == "flaw" else k) for r in keep) for k in ("flaw",) + others}
        lo, hi = exact_interval(count["flaw"], len(keep)) if keep else (0.0, 0.0)
        hours = cpu_hours(settings, rows, c["budget"])
        cpus = sorted({e.get("cpu", "") for e in settings.get("events", []) if e.get("cpu")})
        out[c["name"]] = dict(
            arm=c["arm"],
            seed=c["seed"],
            budget=c["budget"],
            scenarios=len(keep),
            others=list(others),
            **count,
            flaw_per_1000=1000.0 * count["flaw"] / max(1, len(keep)),
            flaw_interval=[1000.0 * lo, 1000.0 * hi],
            modes=fm.distinct(fm.modes_of(camp, keep, lambda r: r.get("attribution") == cls)),
            cpu_hours=hours,
            cpu_measured=measured_cpu_hours(settings) is not None,
            flaw_per_cpu_hour=count["flaw"] / hours if hours else None,
            cpu=", ".join(cpus),
            deviations=[d.split(": ", 1)[1] for d in deviations(p, c, camp, rows) if "of the" not in d]
            + shared[c["name"]],
        )
    return out


def shared_machine(folder: str, names) -> Dict[str, List[str]]:
    """{campaign: its deviations for sharing the machine}: the lines of FOLDER/machine.log (one an
    interval: start, end, what ran beside, the campaigns it overlapped; a line starting with `#` is
    a comment) that
    name the campaign (issue #67: a campaign that ran beside another job is a deviation)."""
    return {n: [f"shared the machine (machine.log line {k})" for k in log_lines(folder, n)] for n in names}


def log_lines(folder: str, name: str) -> List[int]:
    """The numbers of FOLDER/machine.log's lines (not its `#` comments) that name campaign `name`
    (a whole name: `flaw-x-s1` is not named by `flaw-x-s10`); [] without a log."""
    path = os.path.join(folder, "machine.log")
    if not os.path.isfile(path):
        return []
    with open(path, encoding="utf-8") as f:
        lines = ["" if ln.lstrip().startswith("#") else ln.strip() for ln in f]
    pattern = re.compile(rf"(?<![\w-]){re.escape(name)}(?![\w-])")
    return [k for k, line in enumerate(lines, 1) if pattern.search(line)]


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


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="protocol", description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    a = sub.add_parser("plan")
    a.add_argument("protocol")
    a.add_argument("stage", choices=("pilot", "confirmatory"))
    a.add_argument("--choice", default="")
    c = sub.add_parser("choose")
    c.add_argument("protocol")
    c.add_argument("folder")
    t = sub.add_parser("status", help="every campaign so far into the doc's generated block")
    t.add_argument("protocol")
    t.add_argument("folder")
    t.add_argument("--doc", default="")
    t.add_argument("--check", action="store_true", help="only say whether the doc's block is stale (exit 1)")
    t.add_argument("--choice", default="", help="the pilot's choice (default: FOLDER/pilot_choice.json)")
    n = sub.add_parser("analyse")
    n.add_argument("protocol")
    n.add_argument("folder")
    n.add_argument("--json", default="")
    n.add_argument("--doc", default="", help="rewrite the page's result block (and, complete, the coverage map)")
    n.add_argument(
        "--figure",
        default="",
        help="the coverage map's PNG (default: docs/images/NAME_coverage.png, NAME the protocol's; "
        "round 5's: docs/images/flaw_study_coverage.png); the page links it relative to --doc",
    )
    n.add_argument("--check", action="store_true", help="with --doc: only say whether the block is stale (exit 1)")
    n.add_argument("--interim", action="store_true", help="print the comparison before every campaign is in")
    n.add_argument(
        "--choice",
        default="",
        help="the pilot's choice the plan was made with (default: FOLDER/pilot_choice.json; "
        "a study with no pilot of its own names another's, as `plan --choice` did)",
    )
    args = ap.parse_args(argv)
    try:
        p = load(args.protocol)
        if args.cmd == "plan":
            choice = None
            if args.choice:
                with open(args.choice) as f:
                    choice = json.load(f)
            sys.stdout.write(plan_lines(campaigns(p, args.stage, choice)))
            return 0
        if args.cmd == "status":
            block = status_markdown(status(p, args.folder, args.choice), p["name"], class_labels(p)[1])
            if not args.doc:
                print(block)
                return 0
            from asg_analysis.docblocks import rewrite_between as rewrite_block

            return rewrite_block(args.doc, *markers(p)[:2], block, args.check, "protocol status")
        if args.cmd == "choose":
            ch = choose(p, args.folder)
            out = os.path.join(args.folder, "pilot_choice.json")
            with open(out, "w") as f:
                json.dump(ch, f, indent=1, sort_keys=True)
                f.write("\n")
            for d in ch["deviations"]:
                print(f"deviation: {d}")
            what = f"search {ch['search']}, " if "search" in ch else ""
            band = f", route band {ch['band_m']:g} m" if ch.get("band_m") is not None else ""
            print(f"pilot choice: {what}reward {ch['reward']}{band} ({out})")
            return 0
        with open(args.choice or os.path.join(args.folder, "pilot_choice.json")) as f:
            choice = json.load(f)
        res = analyse(p, args.folder, choice)
    except (ProtocolError, OSError, ValueError, KeyError) as e:
        print(f"protocol: {e}", file=sys.stderr)
        return 2
    return report_analysis(p, args, res)


def report_analysis(p: dict, args, res: dict) -> int:
    """`protocol analyse`'s output: deviations, the comparison (withheld until every confirmatory
    campaign is in, unless --interim), the winner, and with --json / --doc the files."""
    for d in res["deviations"]:
        print(f"deviation: {d}")
    withheld = res["complete"] < res["campaigns"] and not args.interim
    if withheld:  # the protocol compares no arm before every confirmatory campaign is in
        print(
            f"comparison withheld: {res['complete']} of the {res['campaigns']} confirmatory campaigns are complete "
            "(--interim prints it anyway, for the operator, not for the answer)"
        )
    for r in [] if withheld else res["comparison"]:
        vs = (
            ""
            if r["p"] is None
            else f"; default / this {r['ratio']:.2f} ({r['ratio_lo']:.2f}-{r['ratio_hi']:.2f}), p = {r['p']:.4f}"
        )
        print(
            f"{r['arm']}: {r['mean']:.2f} per 1,000 ({r['lo']:.2f}-{r['hi']:.2f}) over {r['seeds']} seeds {r['counts']}{vs}"
        )
    if res["winner"]:
        w = res["winner"]
        print(
            f"winner: {w['arm']} ({w['per_cpu_hour']:.1f} {class_labels(p)[0]} per CPU-hour): {' '.join(w['train_args'])}"
        )
    if args.json:
        with open(args.json, "w") as f:
            json.dump(res, f, indent=1, sort_keys=True, default=str)
    if args.doc:
        figure = args.figure or os.path.join(
            REPO,
            "docs",
            "images",
            "flaw_study_coverage.png"
            if p["name"] == "flaw"
            else f"{p['name']}_coverage.png",  # round 5's kept its name
        )
        rel = os.path.relpath(figure, os.path.dirname(os.path.abspath(args.doc)))
        complete = res["complete"] >= res["campaigns"]
        budget, budget_png = "", os.path.join(os.path.dirname(figure), "flaw_study_budget.png")
        if os.path.basename(figure).endswith("coverage.png") and os.path.basename(figure) != "flaw_study_coverage.png":
            budget_png = figure[: -len("coverage.png")] + "budget.png"  # a study of its own: its own pair of figures
        if complete:
            from asg_analysis.studies import flaw_budget

            spent = flaw_budget.read(args.folder, p["budget"], p["name"], p["endpoint"]["class"])
            budget = flaw_budget.markdown(spent, list(p["arms"]))
            if not args.check:
                coverage_figure(res, figure)
                flaw_budget.figure(spent, list(p["arms"]), budget_png)
        from asg_analysis.docblocks import rewrite_between as rewrite_block

        block = result_markdown(
            p,
            res,
            rel if complete else "",
            budget,
            os.path.relpath(budget_png, os.path.dirname(os.path.abspath(args.doc))) if complete else "",
        )
        return rewrite_block(args.doc, *markers(p)[2:], block, args.check, "protocol analyse")
    return 0


if __name__ == "__main__":
    sys.exit(main())
