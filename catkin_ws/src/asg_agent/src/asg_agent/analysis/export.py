"""Reading campaign stores back (no ROS imports): saturation of actions, counts over scenarios.

    python3 -m asg_agent.analysis asp-effect [--scenarios 1000] [--seeds 3] [--out PNG] [--json OUT]
    python3 -m asg_agent.analysis export STORE CAMPAIGN OUT.jsonl.gz
    python3 -m asg_agent.analysis summary EXPORT.jsonl.gz [...]
    python3 -m asg_agent.analysis park STORE CAMPAIGN OUT.tar.xz
    python3 -m asg_agent.analysis unpark STORE PARKED.tar.xz
    python3 -m asg_agent.analysis complete EXPORT.jsonl.gz SCENARIOS   # exit 0: finished, that many

`park` packs an unfinished campaign (its rows and its checkpoint) into one file to carry to
another machine or checkout; `unpark` puts it back into a store, and `--resume` goes on from it.

`asp-effect` measures what the action saturation penalty does: TD3-PER with and without it,
run against the in-process stand-in simulator (fake_pool: cheap, so several seeds of 1,000
scenarios take a minute), reporting the fraction of action coordinates at the edge of their
range (|a| >= 0.99, an obstacle within 0.5 % of the landscape's border) per 100 scenarios.
"""

import argparse
import io
import json
import os
import sys
import tempfile
from typing import List, Optional

import numpy as np

from asg_agent.campaign.store import (
    DIFFERENTIAL,
    Store,
    StoreError,
    attribute,
    checkpoint_path,
    park,
    unpack_trajectory,
    unpark,
)
from asg_agent.scoring.attribution import FINDING, FINDING_STRONG, count_classes


def actions_of(store: Store, campaign: str, size: float) -> np.ndarray:
    """(jobs, 2n) actions in [-1, 1] recovered from the stored requests."""
    out = []
    for r in store.rows(campaign):
        req = json.loads(r["request"])
        xy = [(i["x"], i["y"]) for l in req["structural"]["layouts"] for i in l["instances"]]
        out.append(np.asarray(xy, np.float64).ravel() / size * 2.0 - 1.0)
    return np.asarray(out)


def saturated_fraction(actions: np.ndarray, window: int = 100, edge: float = 0.99) -> List[float]:
    sat = (np.abs(actions) >= edge).mean(axis=1)
    return [float(sat[k : k + window].mean()) for k in range(0, len(sat), window)]


def collision_index(request: dict, collision_with: str) -> Optional[int]:
    """The store's "layout:instance" of the obstacle a run collided with, as an index into the
    export's flat `positions` / `meshes` lists; None when the run hit nothing (or an old row)."""
    if not collision_with:
        return None
    try:
        layout, instance = (int(v) for v in collision_with.split(":"))
    except ValueError:
        raise ValueError(f"collision_with {collision_with!r} is not 'layout:instance'") from None
    layouts = request["structural"]["layouts"]
    if not (0 <= layout < len(layouts) and 0 <= instance < len(layouts[layout]["instances"])):
        raise ValueError(f"collision_with {collision_with!r} names no obstacle of the request")
    return sum(len(l["instances"]) for l in layouts[:layout]) + instance


def export(store: Store, campaign: str, out: str, hz: float = 10.0) -> int:
    """A compact export of a campaign (gzip JSON lines, a few hundred bytes a scenario): the
    campaign row first, then per scenario its job, episode, step, obstacle positions, every proxy
    term, termination, the obstacle hit (`collision_with`, an index into `positions`) and the
    trajectory at `hz` (x, y to 1 cm). Enough to recompute every count
    and draw every figure without the store; the store keeps the full requests and 60 Hz
    trajectories for exact replays."""
    import gzip

    c = store.campaign(campaign)
    if c is None:
        raise ValueError(f"no campaign {campaign!r} in {store.path}")
    n = 0
    # mtime 0 and no file name in the gzip header: the same campaign exports to the same bytes.
    with (
        open(out, "wb") as raw,
        gzip.GzipFile(filename="", mode="wb", fileobj=raw, mtime=0) as gz,
        io.TextIOWrapper(gz, encoding="utf-8") as f,
    ):
        f.write(json.dumps({"campaign": c}) + "\n")
        for r in store.rows(campaign):
            req = json.loads(r["request"])
            traj = unpack_trajectory(r["trajectory"])
            step = max(1, int(round(60.0 / hz)))
            keep = np.r_[traj[::step], traj[-1:]]
            f.write(
                json.dumps(
                    {
                        "job": r["job"],
                        "episode": r["episode"],
                        "step": r["step"],
                        "worker": r["worker"],
                        "scenario_id": r["scenario_id"],
                        "termination": r["termination"],
                        "error": r["error"],
                        "proxy": r["proxy"],
                        "vis": r["vis"],
                        "yaw_term": r["yaw_term"],
                        "plr": r["plr"],
                        "path_length": r["path_length"],
                        "optimal_length": r["optimal_length"],
                        "sim_time": r["sim_time"],
                        "positions": [
                            [round(i["x"], 3), round(i["y"], 3)]
                            for l in req["structural"]["layouts"]
                            for i in l["instances"]
                        ],
                        "meshes": [l["mesh_name"] for l in req["structural"]["layouts"] for _ in l["instances"]],
                        # the obstacle the run collided with: an index into positions and meshes
                        "collision_with": collision_index(req, r["collision_with"]),
                        "textural": req["textural"],
                        # issue #27: the ground's shape (absent: the flat ground)
                        **({"terrain": req["structural"]["terrain"]} if req["structural"].get("terrain") else {}),
                        "visibility": json.loads(r["visibility"]),
                        "wall_time": round(r["wall_time"], 3),
                        "removed": json.loads(r["removed"]),
                        "finished": round(r["finished"], 2),
                        "attempts": r["attempts"],
                        "reward": r["reward"],
                        "reference": json.loads(r["reference"]) if r["reference"] else None,
                        # issue #36: named reference stacks ({role: run}) and the class
                        **(
                            {"attribution": r["attribution"]}
                            | ({"reference_runs": json.loads(r["reference_runs"])} if r["reference_runs"] else {})
                            if r["attribution"]
                            else {}
                        ),
                        "trajectory_xy": np.round(keep[:, 1:3], 2).tolist(),
                    }
                )
                + "\n"
            )
            n += 1
    return n


def top_down(store: Store, campaign: str, job: int, out: str):
    """Top-down summary of one stored scenario, like the paper's Figures 5-8: obstacles by type
    (removed ones dashed), the driven path, the optimal path dashed, start and goal circles, the
    proxy and its terms in the title."""
    from asg_scenario.report import plot_run
    from asg_agent.scoring.proxy import optimal_path, placed_mask

    row = next((r for r in store.rows(campaign, job - 1) if r["job"] == job), None)
    if row is None:
        raise ValueError(f"campaign {campaign!r} has no job {job}")
    req = json.loads(row["request"])
    removed_list = json.loads(row["removed"])
    removed = {(l, i) for l, i, _ in removed_list}
    opt = optimal_path(req, placed_mask(req, removed_list))
    traj = unpack_trajectory(row["trajectory"])
    title = (
        f"{campaign} job {job} (store id {row['id']})\nproxy {row['proxy']:.2f} = 0.1 x vis {row['vis']:+.2f} "
        f"+ yaw term {row['yaw_term']:.2f} + PLR {row['plr']:.3f}^2\n{row['termination']} after "
        f"{row['sim_time']:.1f} s, driven {row['path_length']:.1f} m, optimal {row['optimal_length']:.1f} m"
    )
    others = []
    if row["reference_runs"]:  # three-stack attribution: the references' paths on the same scene
        colours = {"full": "tab:blue", "ground_truth": "tab:green"}
        for role, run in sorted(json.loads(row["reference_runs"]).items()):
            p = "n/a" if run.get("proxy") is None else f"{run['proxy']:.2f}"
            others.append((f"{role}: {run['termination']}, proxy {p}", run["trajectory_xy"], colours.get(role, "0.5")))
        title += f"\nattribution: {row['attribution']}"
    plot_run(
        out,
        req,
        traj[:, 1:3].tolist(),
        title=title,
        removed=removed,
        optimal=opt.points,
        label="under test" if others else "vehicle",
        others=others,
    )


def read_export(path: str):
    import gzip

    with gzip.open(path, "rt", encoding="utf-8") as f:
        head = json.loads(f.readline())
        rows = [json.loads(line) for line in f]
    return head["campaign"], rows


def counts(rows) -> dict:
    """Counts of an export; with attribution (rows carrying the reference stack's run) also the
    findings that are the perception's (proxy >= 3, reference < 2), the stack's (both >= 3), the
    differential ones (proxy - reference >= 1), and the collisions that are the perception's
    (the reference drove through) or the stack's (both collided), as the store's summary counts them."""
    p = [r["proxy"] for r in rows if r["proxy"] is not None]
    out = {
        "scenarios": len(rows),
        "proxy_ge_3": sum(v >= FINDING for v in p),
        "proxy_ge_4": sum(v >= FINDING_STRONG for v in p),
        "max_proxy": max(p) if p else None,
        "terminations": {t: sum(r["termination"] == t for r in rows) for t in sorted({r["termination"] for r in rows})},
    }
    pairs = [
        (r["proxy"], r["reference"]["proxy"])
        for r in rows
        if r["proxy"] is not None and r.get("reference") and r["reference"].get("proxy") is not None
    ]
    if pairs:
        kinds = [attribute(t, ref) for t, ref in pairs]
        out.update(
            attributed=len(pairs),
            perception_ge3=sum(k[1] for k in kinds),
            stack_ge3=sum(k[2] for k in kinds),
            differential_ge1=sum(t - ref >= DIFFERENTIAL for t, ref in pairs),
        )
    refs = [(r["termination"], r["reference"].get("termination")) for r in rows if r.get("reference")]
    if refs:
        out.update(
            perception_collisions=sum(t == "COLLISION" and ref == "SUCCESS" for t, ref in refs),
            stack_collisions=sum(t == "COLLISION" and ref == "COLLISION" for t, ref in refs),
        )
    labels = [r["attribution"] for r in rows if r.get("attribution")]
    if labels:
        out["classes"] = count_classes(labels)
    return out


def asp_effect(scenarios: int, seeds: int, experiment: str):
    from asg_agent.campaign.loop import Campaign
    from asg_agent.campaign.experiment import load_experiment
    from asg_agent.campaign.fake_pool import FakePool
    from asg_agent.search.methods import make_method

    exp = load_experiment(experiment)
    folder = tempfile.mkdtemp()
    store = Store(os.path.join(folder, "asp.sqlite"))
    curves = {}
    for method in ("td3-per-asp", "td3-per"):
        for seed in range(seeds):
            name = f"{method}-s{seed}"
            c = Campaign(
                name,
                exp,
                make_method(method, exp, seed, budget=scenarios),
                store,
                FakePool(2, seed=seed),
                scenarios,
                seed,
                os.path.join(folder, name + ".ckpt"),
                slots=4,
                checkpoint_every=10**9,
            )
            c.start()
            c.run(poll_timeout=0.0)
            curves[name] = saturated_fraction(actions_of(store, name, exp.size))
            print(
                f"{name}: saturated fraction per 100 scenarios " + " ".join(f"{v:.2f}" for v in curves[name]),
                file=sys.stderr,
            )
    return curves


def main(argv=None):
    p = argparse.ArgumentParser(prog="asg_agent.analysis")
    sub = p.add_subparsers(dest="cmd", required=True)
    a = sub.add_parser("asp-effect", help="saturated-action fraction with and without ASP (stand-in simulator)")
    a.add_argument("--scenarios", type=int, default=1000)
    a.add_argument("--seeds", type=int, default=3)
    a.add_argument(
        "--experiment",
        default=os.path.join(os.path.dirname(__file__), "..", "..", "..", "..", "..", "..", "experiments", "exp1.yaml"),
    )
    a.add_argument("--json", default="")
    a.add_argument("--out", default="", help="PNG of the curves")
    e = sub.add_parser("export", help="compact gzip JSON-lines export of a campaign")
    e.add_argument("store")
    e.add_argument("campaign")
    e.add_argument("out")
    fg = sub.add_parser("figure", help="top-down PNG of the top-k scenarios of a campaign")
    fg.add_argument("store")
    fg.add_argument("campaign")
    fg.add_argument("--top", type=int, default=1)
    fg.add_argument("--out", default="figures", help="folder for CAMPAIGN_jobN.png")
    sm = sub.add_parser("summary", help="counts of exported campaigns")
    sm.add_argument("exports", nargs="+")
    pk = sub.add_parser("park", help="pack an unfinished campaign (rows and checkpoint) into one tar.xz")
    pk.add_argument("store")
    pk.add_argument("campaign")
    pk.add_argument("out")
    pk.add_argument(
        "--unfinished-only",
        action="store_true",
        help="do nothing (exit 0) for a campaign the store lacks or that has finished",
    )
    cp = sub.add_parser("complete", help="exit 0 when an export is of a finished campaign of >= SCENARIOS")
    cp.add_argument("export")
    cp.add_argument("scenarios", type=int)
    up = sub.add_parser("unpark", help="put a parked campaign back into a store (left alone if it holds it)")
    up.add_argument("store")
    up.add_argument("parked")
    args = p.parse_args(argv)
    if args.cmd in ("park", "unpark"):
        try:
            if args.cmd == "park":
                store = Store(args.store)
                c = store.campaign(args.campaign)
                if args.unfinished_only and (c is None or c["finished"]):
                    print(f"{args.campaign}: " + ("not in the store" if c is None else "finished") + "; not parked")
                    return 0
                n = park(store, args.campaign, checkpoint_path(args.store, args.campaign), args.out)
                print(f"{args.out}: campaign {args.campaign}, {n} scenarios and its checkpoint")
            else:
                n = unpark(Store(args.store), args.parked)
                print(
                    f"{args.parked}: "
                    + (
                        "the store already holds this campaign; left alone"
                        if n is None
                        else f"{n} scenarios and the checkpoint restored into {args.store}"
                    )
                )
        except StoreError as e:
            print(f"error: {e}", file=sys.stderr)
            return 2
        return 0
    if args.cmd in ("export", "figure"):
        try:
            store = Store(args.store, create=False)
        except StoreError as e:
            print(f"error: {e}", file=sys.stderr)
            return 2
    if args.cmd == "export":
        n = export(store, args.campaign, args.out)
        print(f"{args.out}: {n} scenarios")
        return 0
    if args.cmd == "figure":
        os.makedirs(args.out, exist_ok=True)
        for r in store.summary(args.campaign, top=args.top)["top"]:
            path = os.path.join(args.out, f"{args.campaign}_job{r['job']}.png")
            top_down(store, args.campaign, r["job"], path)
            print(path)
        return 0
    if args.cmd == "complete":
        if not os.path.isfile(args.export):
            return 1
        c, rows = read_export(args.export)
        return 0 if c["finished"] and len(rows) >= args.scenarios else 1
    if args.cmd == "summary":
        for path in args.exports:
            c, rows = read_export(path)
            print(json.dumps({"campaign": c["name"], **counts(rows)}))
        return 0
    curves = asp_effect(args.scenarios, args.seeds, args.experiment)
    if args.json:
        os.makedirs(os.path.dirname(os.path.abspath(args.json)), exist_ok=True)
        with open(args.json, "w") as f:
            json.dump(curves, f, indent=1)
    if args.out:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6, 3.2))
        for method, colour in (("td3-per-asp", "tab:blue"), ("td3-per", "tab:red")):
            runs = np.array([v for k, v in curves.items() if k.startswith(method + "-s")])
            x = (np.arange(runs.shape[1]) + 0.5) * 100
            ax.plot(x, runs.mean(0), color=colour, label=f"{method} (mean of {len(runs)} seeds)")
            ax.fill_between(x, runs.min(0), runs.max(0), color=colour, alpha=0.2)
        ax.set_xlabel("scenarios")
        ax.set_ylabel("action coordinates at |a| >= 0.99")
        ax.set_ylim(0, 1)
        ax.legend(fontsize=8)
        ax.set_title("Action saturation with and without ASP (stand-in simulator)", fontsize=9)
        fig.tight_layout()
        fig.savefig(args.out, dpi=120)
    summary = {
        m: float(np.mean([v[-1] for k, v in curves.items() if k.startswith(m + "-s")]))
        for m in ("td3-per-asp", "td3-per")
    }
    print(json.dumps({"final_saturated_fraction": summary}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
