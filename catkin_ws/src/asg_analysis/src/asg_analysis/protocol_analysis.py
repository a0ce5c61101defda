"""A protocol's campaigns read back against it (no ROS): each campaign's endpoint per seed, its
deviations from the protocol (interruptions, a shared machine, a wrong setting), its CPU-hours,
the pilot's choice by the protocol's stated rule, and the confirmatory comparison (statistics from
asg_analysis.stats). asg_analysis.protocol plans the campaigns; asg_analysis.protocol_pages
writes what this computes."""

import json
import os
import re
from typing import Dict, List, Optional

from asg_agent.scoring import attribution as attr
from asg_analysis.protocol import ATTRIBUTION_ROLES, campaigns, train_args


def other_classes(cls: str):
    """The attribution's classes shown beside the endpoint's: model and stack findings beside flaw
    findings (three-stack attribution), shared failures beside regressions (a stack pair)."""
    return {"regression": ("shared",)}.get(cls, ("model", "stack"))


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


def status(p: dict, folder: str, choice_path: str = "") -> dict:
    """Every campaign of the protocol so far, each with its endpoint (first `budget` scenarios),
    cost and interruptions; nothing compared (that waits for complete stages). The confirmatory
    campaigns are those of the pilot's choice, `choice_path` (default FOLDER/pilot_choice.json);
    the endpoint's class is counted under the `flaw` keys, whatever the class (a stack pair's
    regressions), beside the other classes of the attribution."""
    from asg_agent.records import failure_modes as fm
    from asg_agent.records.export import read_export
    from asg_analysis.stats import exact_interval

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
