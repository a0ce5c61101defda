"""baseline: what the stacks under test do on seeded random layouts of an experiment (issue #23).

A finding is only as good as its baseline: with perfect perception the stack must drive close to
the optimal path, and what a flawed perception changes is measured on the same layouts. The
layouts are those uniform random search proposes with seed 0 (job k of `random`, seed 0, is
layout k), so a baseline of N layouts is the first N scenarios of that campaign.

    python3 -m asg_agent.cli.baseline run EXPERIMENT.yaml --stack ground_truth --layouts 500 --workers 2
    python3 -m asg_agent.cli.baseline summary EXPERIMENT.yaml      # results/baseline/<exp>.json + table
    python3 -m asg_agent.cli.baseline compare A.jsonl B.jsonl      # how many proxies move between two
    python3 -m asg_agent.cli.baseline offline EXPERIMENT.yaml --label reference \
        --planner catkin_ws/src/asg_planner/config/planner_reference.yaml   # a planner variant, no ROS

`run` talks to running workers (scripts/repro/baseline.sh launches them per stack) and appends one JSON
line per layout to results/baseline/<exp>/<stack>.jsonl as each run ends, so an interrupted run
resumes where it stopped. `summary` needs no ROS. `offline` runs the ground-truth stack on the
same layouts without ROS, through asg_planner_harness's `asg_closed_loop` (the same cores in the lockstep
order; its proxies equal the ROS stack's), for a planner or follower variant: it writes
results/baseline/<exp>/offline/<label>.jsonl and compares it with the stored ground-truth rows.
"""

import argparse
import json
import os
import sys
from typing import Dict, List

import numpy as np

from asg_agent.campaign.dispatch import run_each
from asg_agent.records.experiment import load_experiment
from asg_agent.scoring.proxy import run_terms
from asg_agent.search.methods import RandomSearch
from asg_agent.records.store import attribute
from asg_agent.scoring.attribution import FINDING

from asg_agent.paths import REPO

STACKS = (
    "ground_truth",
    "flawed",
    "full",
    "flawed_lite",
    "full_lite",
    "flawed_tw",
    "full_tw",
    "depth",
    "flawed_hf1",
    "flawed_hr1",
)  #: labels: ground truth, a shipped model's name (flawed_hf1, flawed_hr1: hardened, issue #40), or depth (issue #39)
BOUNDS = {"share_ge3": 0.01, "median_yaw_term": 0.2, "median_plr": 1.03, "collision_share": 0.005}  # issue #23


def layouts(exp, n: int) -> List[dict]:
    """The first n scenarios of uniform random search with seed 0 on this experiment."""
    m = RandomSearch(exp, 0)
    steps = exp.episode_steps
    return [exp.request(m.propose(k, k // steps, k % steps, None), scenario_id=k + 1) for k in range(n)]


def default_root() -> str:
    """Where rows go without --root: the repository's results/baseline when this code runs from a
    clone, else (an install space) ~/.ros/asg/baseline, beside train.launch's default store."""
    if os.path.isdir(os.path.join(REPO, "catkin_ws")):
        return os.path.join(REPO, "results", "baseline")
    return os.path.join(os.path.expanduser("~"), ".ros", "asg", "baseline")


def out_path(exp_name: str, stack: str, root: str = "") -> str:
    return os.path.join(root or default_root(), exp_name, f"{stack}.jsonl")


def read_rows(path: str) -> Dict[int, dict]:
    rows = {}
    if os.path.isfile(path):
        with open(path) as f:
            for line in f:
                if line.strip():
                    r = json.loads(line)
                    rows[r["layout"]] = r
    return rows


def row_of(k: int, req: dict, o) -> dict:
    """One layout's result: every proxy term, or the error."""
    terms = run_terms(req, o, dtype=np.float64)[1]
    r = {
        "layout": k,
        "termination": o.termination,
        "error": o.error,
        "collision_with": o.collision_with,
        "sim_time": round(float(o.sim_time), 4),
    }
    for key in ("proxy", "vis", "yaw_term", "plr", "path_length", "optimal_length"):
        r[key] = None if terms is None else round(float(getattr(terms, key)), 6)
    return r


def run(a) -> int:
    from asg_agent.campaign.policy import worker_names
    from asg_agent.ros.pool import WorkerPool
    from tqdm import tqdm

    exp = load_experiment(a.experiment)
    reqs = layouts(exp, a.layouts)
    path = out_path(exp.name, a.stack, a.root)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    done = read_rows(path)
    todo = [k for k in range(a.layouts) if k not in done]
    print(
        f"{exp.name}/{a.stack}: {len(done)} of {a.layouts} layouts stored in {path}, {len(todo)} to run",
        file=sys.stderr,
    )
    if not todo:
        return 0
    from asg_agent.ros.node import init_node

    init_node("baseline", anonymous=True, disable_signals=True)
    pool = WorkerPool(worker_names(a.workers), answer_timeout=300.0)
    bar = tqdm(total=len(todo), desc=f"{exp.name}/{a.stack}", unit="run", dynamic_ncols=True)
    with open(path, "a") as f:

        def on_row(k, o):
            r = dict(row_of(k, reqs[k], o), stack=a.stack)
            f.write(json.dumps(r, sort_keys=True) + "\n")
            f.flush()
            bar.update(1)
            bar.set_postfix_str(
                f"{r['termination']} proxy {r['proxy'] if r['proxy'] is None else round(r['proxy'], 2)}"
            )

        run_each(pool, reqs, on_row, keys=todo)  # campaign.dispatch: retries elsewhere, late answers dropped
    bar.close()
    return 0


def closed_loop_tool() -> str:
    """asg_planner_harness's asg_closed_loop, found as ROS finds executables (asg_scenario.binaries;
    an exec_depend of asg_agent), or $ASG_CLOSED_LOOP."""
    from asg_scenario.binaries import BinaryNotFound, find_binary

    tool = os.environ.get("ASG_CLOSED_LOOP")
    try:
        tool = tool or find_binary("asg_planner_harness", "asg_closed_loop")
    except BinaryNotFound as e:
        raise SystemExit(f"baseline offline: {e}, or set ASG_CLOSED_LOOP") from None
    if not os.access(tool, os.X_OK):
        raise SystemExit(f"baseline offline: ASG_CLOSED_LOOP={tool} is not an executable")
    return tool


def offline_rows(reqs: List[dict], todo: List[int], planner: str, sets: List[str], jobs: int, tmp: str, on_row) -> None:
    """Runs reqs[k] for k in todo through asg_closed_loop, in `jobs` processes (one llvmpipe
    thread each); on_row(k, row) as each process's batch ends."""
    import subprocess
    from concurrent.futures import ThreadPoolExecutor
    from types import SimpleNamespace
    from asg_scenario.schema import dump_scenario

    tool = closed_loop_tool()
    args = (["--planner", planner] if planner else []) + sum((["--set", kv] for kv in sets), [])
    files = {}
    for k in todo:
        files[k] = os.path.join(tmp, f"layout-{k}.yaml")
        with open(files[k], "w") as f:
            f.write(dump_scenario(reqs[k]))
    env = dict(os.environ, LP_NUM_THREADS="1")

    def batch(ks):
        for i in range(0, len(ks), 25):  # small batches: rows come back as they finish
            chunk = ks[i : i + 25]
            res = subprocess.run(
                [tool, *args, "--out", tmp, *[files[k] for k in chunk]], capture_output=True, text=True, env=env
            )
            if res.returncode:
                raise SystemExit(f"baseline offline: asg_closed_loop failed: {res.stderr.strip()[-2000:]}")
            for k, line in zip(chunk, res.stdout.splitlines()):
                j = json.loads(line)
                tr = np.loadtxt(os.path.join(tmp, f"{j['name']}.csv"), delimiter=",", skiprows=1, ndmin=2)
                o = SimpleNamespace(
                    termination=j["termination"],
                    error=j.get("error", ""),
                    collision_with=j.get("collision_with", ""),
                    sim_time=j["sim_time"],
                    visibility=j["visibility"],
                    removed=j["removed"],
                    trajectory=tr.ravel(),
                )
                on_row(k, o)

    with ThreadPoolExecutor(jobs) as ex:
        list(ex.map(batch, [todo[w::jobs] for w in range(jobs)]))


def offline(a) -> int:
    import tempfile
    import threading
    from tqdm import tqdm

    exp = load_experiment(a.experiment)
    reqs = layouts(exp, a.layouts)
    path = os.path.join(os.path.dirname(out_path(exp.name, "ground_truth", a.root)), "offline", f"{a.label}.jsonl")
    os.makedirs(os.path.dirname(path), exist_ok=True)
    done = read_rows(path)
    todo = [k for k in range(a.layouts) if k not in done]
    print(
        f"{exp.name}/offline/{a.label}: {len(done)} of {a.layouts} layouts stored in {path}, {len(todo)} to run",
        file=sys.stderr,
    )
    lock = threading.Lock()
    bar = tqdm(total=len(todo), desc=f"{exp.name}/{a.label}", unit="run", dynamic_ncols=True, disable=not todo)
    with open(path, "a") as f, tempfile.TemporaryDirectory(prefix="asg_offline_") as tmp:

        def on_row(k, o):
            r = dict(row_of(k, reqs[k], o), stack=f"ground_truth/{a.label}", planner=a.planner, set=a.set)
            with lock:
                f.write(json.dumps(r, sort_keys=True) + "\n")
                f.flush()
                done[k] = r
                bar.update(1)

        if todo:
            offline_rows(reqs, todo, a.planner, a.set, a.jobs, tmp, on_row)
    bar.close()
    rows = [done[k] for k in range(a.layouts)]
    g = stack_summary(rows)
    ref = read_rows(out_path(exp.name, "ground_truth", a.root))
    both = [k for k in range(a.layouts) if k in ref and ref[k]["proxy"] is not None and done[k]["proxy"] is not None]
    d = np.array([done[k]["proxy"] - ref[k]["proxy"] for k in both])
    print(
        f"| {a.label} | {100 * g['share_ge3']:.1f} % | {g['median_yaw_term']:.3f} / {g['p90_yaw_term']:.3f} | "
        f"{g['median_plr']:.3f} / {g['p90_plr']:.3f} | {g['collisions']} | "
        + (f"{100 * (abs(d) > 0.1).mean():.1f} % ({abs(d).max():.2f}) of {len(both)} |" if len(both) else "- |")
    )
    return 0


def compare(a_path: str, b_path: str, threshold: float = 0.1) -> dict:
    """Two row files of the same layouts (two backends, two planner variants): how many layouts
    both ran, the share whose proxy moves by more than `threshold`, the largest move, and the
    endings that differ."""
    a, b = read_rows(a_path), read_rows(b_path)
    both = sorted(k for k in a if k in b and a[k]["proxy"] is not None and b[k]["proxy"] is not None)
    if not both:
        raise SystemExit(f"baseline compare: no layout with a proxy in both {a_path} and {b_path}")
    d = np.array([b[k]["proxy"] - a[k]["proxy"] for k in both])
    return {
        "layouts": len(both),
        "moved_share": float((np.abs(d) > threshold).mean()),
        "threshold": threshold,
        "largest_move": float(np.abs(d).max()),
        "mean_change": float(d.mean()),
        "endings_differ": [k for k in both if a[k]["termination"] != b[k]["termination"]],
        "collisions": [int(sum(r[k]["termination"] == "COLLISION" for k in both)) for r in (a, b)],
    }


def stack_summary(rows: List[dict]) -> dict:
    ok = [r for r in rows if r["proxy"] is not None]
    p = np.array([r["proxy"] for r in ok])
    y = np.array([r["yaw_term"] for r in ok])
    plr = np.array([r["plr"] for r in ok])
    coll = sum(r["termination"] == "COLLISION" for r in rows)
    return {
        "runs": len(rows),
        "errors": len(rows) - len(ok),
        "share_ge3": float((p >= FINDING).mean()) if len(p) else None,
        "median_proxy": float(np.median(p)) if len(p) else None,
        "median_yaw_term": float(np.median(y)) if len(y) else None,
        "p90_yaw_term": float(np.percentile(y, 90)) if len(y) else None,
        "median_plr": float(np.median(plr)) if len(plr) else None,
        "p90_plr": float(np.percentile(plr, 90)) if len(plr) else None,
        "collisions": int(coll),
        "collision_share": coll / len(rows) if rows else None,
        "success": int(sum(r["termination"] == "SUCCESS" for r in rows)),
        # reached the goal shorter than the optimal path (a run that ended early may: its rest is
        # a straight line to the goal, through what it hit)
        "plr_below_0999": int(sum(r["plr"] < 0.999 and r["termination"] == "SUCCESS" for r in ok)),
    }


def summarize(exp_name: str, root: str = "", ground_truth_root: str = "") -> dict:
    """results/baseline/<exp>.json: per stack its summary, per layout the proxies of every stack,
    and what each U-Net stack changes against ground truth on the layouts both ran. The
    ground-truth rows come from `ground_truth_root` where given (they do not depend on the
    U-Net's backend, so a backend's folder shares the default one's); so do the depth stack's and
    those of every registered stack (stacks/*.launch) that has rows."""
    # A registered stack (stacks/*.launch, issue #55) runs no U-Net either: its rows are shared too.
    registered = registered_labels()
    shared = ("ground_truth", "depth") + registered
    rows = {
        s: read_rows(out_path(exp_name, s, ground_truth_root if s in shared and ground_truth_root else root))
        for s in STACKS + registered
    }
    names = STACKS + tuple(s for s in registered if rows[s])  # a registered stack with no rows adds nothing
    out = {
        "experiment": exp_name,
        "layouts": "uniform random search, seed 0: job k is layout k",
        "bounds_ground_truth": BOUNDS,
        "stacks": {},
        "against_ground_truth": {},
        "per_layout": [],
    }
    for s in names:
        if rows[s]:
            out["stacks"][s] = stack_summary(list(rows[s].values()))
    gt = rows["ground_truth"]
    if "ground_truth" in out["stacks"]:
        g = out["stacks"]["ground_truth"]
        out["ground_truth_within_bounds"] = {k: g[k] is not None and g[k] <= v for k, v in BOUNDS.items()}
    for s in ("flawed", "full"):
        both = [k for k in rows[s] if k in gt and rows[s][k]["proxy"] is not None and gt[k]["proxy"] is not None]
        if not both:
            continue
        d = np.array([rows[s][k]["proxy"] - gt[k]["proxy"] for k in both])
        out["against_ground_truth"][s] = {
            "layouts": len(both),
            "raises_by_0.5": float((d >= 0.5).mean()),
            "raises_by_1": float((d >= 1).mean()),
            "median_change": float(np.median(d)),
            "ge3_here_lt2_ground_truth": int(sum(attribute(rows[s][k]["proxy"], gt[k]["proxy"])[1] for k in both)),
        }
    for k in sorted(set().union(*[set(r) for r in rows.values()])):
        out["per_layout"].append(
            {
                "layout": k,
                **{s: (rows[s][k]["proxy"] if k in rows[s] else None) for s in names},
                **{f"{s}_termination": rows[s][k]["termination"] for s in names if k in rows[s]},
            }
        )
    return out


def table(summary: dict) -> str:
    """The Markdown table of docs/baseline.md for one experiment."""
    lines = [
        f"| {summary['experiment']} stack | runs | proxy >= 3 | median / p90 yaw term | median / p90 PLR "
        "| collisions | PLR < 0.999 |",
        "|---|---|---|---|---|---|---|",
    ]
    for s, g in summary["stacks"].items():
        lines.append(
            f"| {s} | {g['runs']} | {100 * g['share_ge3']:.1f} % | {g['median_yaw_term']:.3f} / "
            f"{g['p90_yaw_term']:.3f} | {g['median_plr']:.3f} / {g['p90_plr']:.3f} | {g['collisions']} "
            f"({100 * g['collision_share']:.1f} %) | {g['plr_below_0999']} |"
        )
    for s, d in summary["against_ground_truth"].items():
        lines.append(
            f"\n{s} against ground truth on the same {d['layouts']} layouts: the proxy rises by >= 0.5 on "
            f"{100 * d['raises_by_0.5']:.1f} % and by >= 1 on {100 * d['raises_by_1']:.1f} % of them; "
            f"{d['ge3_here_lt2_ground_truth']} reach 3 where ground truth stays below 2."
        )
    return "\n".join(lines)


def summary_cmd(a) -> int:
    exp = load_experiment(a.experiment)
    s = summarize(exp.name, a.root, a.ground_truth_root)
    path = os.path.join(a.root or default_root(), f"{exp.name}.json")
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        json.dump(s, f, indent=1, sort_keys=True)
        f.write("\n")
    print(table(s))
    print(f"\n{path}")
    return 0


def registered_labels() -> tuple:
    """The names of the stacks registered in stacks/ (issue #55) that are not labels already."""
    from asg_agent.records import stacks

    names = sorted(f[: -len(".launch")] for f in os.listdir(stacks.builtin_dir()) if f.endswith(".launch"))
    return tuple(n for n in names if n not in STACKS and n != "paper")


def stack_label(stack: str) -> str:
    """The label rows are stored under: a label of STACKS, a registered stack's name, or, for the
    path of a registration launch file (a user's stack, docs/your-stack.md), the name it
    registers. ValueError naming what is allowed."""
    if stack in STACKS:
        return stack
    from asg_agent.records import stacks

    try:
        return stacks.load(stack).name
    except stacks.RegistrationError as e:
        raise ValueError(
            f"--stack {stack!r}: one of {', '.join(STACKS + registered_labels())}, or the path of a stack's "
            f"registration launch file ({e})"
        ) from None


def main(argv=None):
    p = argparse.ArgumentParser(prog="baseline", description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run", help="run the layouts on running workers of one stack")
    r.add_argument("experiment")
    r.add_argument(
        "--stack",
        required=True,
        help="which stack the workers run: a label (a perception of the paper's stack: "
        + ", ".join(STACKS)
        + "), a registered stack's name ("
        + ", ".join(registered_labels())
        + ") or the path of a stack's registration launch file (its rows are stored under its name)",
    )
    r.add_argument("--layouts", type=int, default=500, help="layouts 0..N-1")
    r.add_argument("--workers", default="2", help="count or comma-separated namespaces")
    r.add_argument(
        "--root", default="", help="results folder (default results/baseline of a clone, else ~/.ros/asg/baseline)"
    )
    s = sub.add_parser("summary", help="results/baseline/<exp>.json and the Markdown table")
    s.add_argument("experiment")
    s.add_argument("--root", default="")
    s.add_argument("--ground-truth-root", default="", help="where the ground-truth rows are, if not under --root")
    o = sub.add_parser("offline", help="a planner variant on the layouts with ground-truth labels, no ROS")
    o.add_argument("experiment")
    o.add_argument("--label", required=True, help="name of the variant (results/baseline/<exp>/offline/LABEL.jsonl)")
    o.add_argument("--planner", default="", help="planner YAML (default: asg_closed_loop's, planner.yaml's values)")
    o.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="planner parameter, repeatable")
    o.add_argument("--layouts", type=int, default=500, help="layouts 0..N-1")
    o.add_argument("--jobs", type=int, default=2, help="processes side by side")
    o.add_argument("--root", default="")
    c = sub.add_parser("compare", help="two row files of the same layouts: how many proxies move")
    c.add_argument("a", help="rows (jsonl), e.g. results/baseline/exp1/flawed.jsonl")
    c.add_argument("b", help="rows (jsonl) to compare with them")
    c.add_argument("--threshold", type=float, default=0.1, help="a proxy moves when it changes by more")
    a = p.parse_args(argv)
    if a.cmd == "compare":
        for f in (a.a, a.b):
            if not os.path.isfile(f):
                p.error(f"{f}: no such file")
        r = compare(a.a, a.b, a.threshold)
        print(
            f"{r['layouts']} layouts: the proxy moves by > {r['threshold']:g} on {100 * r['moved_share']:.1f} % "
            f"(largest {r['largest_move']:.2f}, mean change {r['mean_change']:+.3f}); collisions "
            f"{r['collisions'][0]} -> {r['collisions'][1]}; endings differ on {len(r['endings_differ'])}: "
            f"{r['endings_differ'][:20]}"
        )
        return 0
    if getattr(a, "layouts", 1) < 1:
        p.error("--layouts must be >= 1")
    if a.cmd == "offline":
        if a.jobs < 1:
            p.error("--jobs must be >= 1")
        if a.planner and not os.path.isfile(a.planner):
            p.error(f"--planner {a.planner}: no such file")
        bad = [kv for kv in a.set if "=" not in kv]
        if bad:
            p.error(f"--set {bad[0]}: expected KEY=VALUE")
        return offline(a)
    if a.cmd == "run":
        try:
            a.stack = stack_label(a.stack)
        except ValueError as e:
            p.error(str(e))
        return run(a)
    return summary_cmd(a)


if __name__ == "__main__":
    sys.exit(main())
