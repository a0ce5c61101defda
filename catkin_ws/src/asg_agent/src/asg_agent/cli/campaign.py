"""campaign: run (or resume) a scene-generation campaign against running scene workers.

    campaign EXPERIMENT.yaml [--method td3-per-asp] [--scenarios 500] [--workers 2]
             [--store results/campaigns.sqlite] [--name NAME] [--seed 0] [--resume]

Workers are the namespaces /worker_0 .. /worker_{N-1} (or a comma-separated list of
namespaces), started by `roslaunch launch/worker.launch ns:=worker_i ...` on this host or any
other host of the same ROS master, or by launch/train.launch. `--fake-workers N` runs an
in-process stand-in instead (no ROS, no simulator: a smoke test of the loop). Prints a progress
bar and ends with a summary (counts of proxy >= 3 and >= 4, the largest proxy, the top 10).
"""

import argparse
import json
import math
import os
import sys
import time

from asg_agent.campaign.loop import REWARDS, Campaign
from asg_agent.campaign.experiment import ExperimentError, load_experiment
from asg_agent.search.methods import METHODS, make_method
from asg_agent.campaign.store import Store, StoreError, checkpoint_path
from asg_agent.search.td3 import TD3Config


def open_tensorboard(a, store, name, c):
    """The campaign's TensorBoard log; a resumed one continues at its first job not yet learnt
    from, with the running counts of the jobs before it."""
    from asg_agent.campaign.tensorboard_log import TensorBoardLog

    logdir = a.tensorboard or os.path.join(os.path.dirname(os.path.abspath(a.store)), "tensorboard", name)
    prior = [dict(r) for r in store.rows(name) if r["job"] < c.next_apply]
    try:
        return TensorBoardLog(logdir, purge_step=c.next_apply, prior_rows=prior)
    except RuntimeError as e:
        print(f"campaign: {e}; going on without it", file=sys.stderr)
        return None


def parse(argv):
    p = argparse.ArgumentParser(prog="campaign", description=__doc__.split("\n\n")[0])
    p.add_argument("experiment", help="experiment file (experiments/expN.yaml)")
    p.add_argument("--method", default="td3-per-asp", choices=METHODS)
    p.add_argument("--scenarios", type=int, default=500, help="scenarios to run in all (default 500)")
    p.add_argument("--workers", default="2", help="worker count N (/worker_0..N-1) or namespaces, comma-separated")
    p.add_argument("--store", default="results/campaigns.sqlite", help="SQLite scenario store")
    p.add_argument("--name", default="", help="campaign name (default: EXPERIMENT-METHOD-sSEED)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--resume", action="store_true", help="continue the named campaign from its checkpoint")
    p.add_argument("--slots", type=int, default=0, help="episodes in flight (default: 2 x workers)")
    p.add_argument("--checkpoint-every", type=int, default=10, help="checkpoint every N finished episodes")
    p.add_argument(
        "--answer-timeout",
        type=float,
        default=300.0,
        help="[s, wall] a worker that has not answered by then is reported and its job re-queued",
    )
    p.add_argument(
        "--updates-per-step",
        type=int,
        default=0,
        help="TD3 methods: gradient updates per observed transition (default: TD3Config's)",
    )
    p.add_argument(
        "--bc-weight",
        type=float,
        default=1.0,
        help="TD3 methods: weight of the behaviour-regularisation term (default 1, the setting of "
        "every documented campaign; 0: off, the variant that collapses to the border)",
    )
    p.add_argument("--fake-workers", type=int, default=0, help="N in-process stand-in workers (no ROS)")
    p.add_argument(
        "--reference-workers",
        default="",
        help="attribution: every scenario also runs on these workers (count, as --workers, "
        "numbered after them, or namespaces), the reference stack (ground-truth labels, "
        "the same planner and follower); each finding is counted as the perception's "
        "(reference proxy < 2) or the stack's (reference proxy >= 3)",
    )
    p.add_argument(
        "--reward",
        default="proxy",
        choices=REWARDS,
        help="what the search maximises: the stack under test's proxy (the paper), "
        "proxy - reference proxy (differential; needs --reference-workers), or the proxy plus "
        "--collision-bonus when the stack under test collided and the reference reached the goal (collision)",
    )
    p.add_argument(
        "--collision-bonus",
        type=float,
        default=2.0,
        help="[-] --reward collision: added to the proxy of a collision (default 2: a collision "
        "on a route of PLR 1 scores about 3, a finding)",
    )
    p.add_argument(
        "--stage-report",
        default="",
        help="write where the time went (per-scenario stage breakdown, rate, inference bound) "
        "to this JSON file at the end (`bench`, docs/benchmarks.md)",
    )
    p.add_argument(
        "--no-early-dispatch",
        action="store_true",
        help="benchmark baseline: give freed workers their next job only after the agent has "
        "learnt from the results (the order before issue #13)",
    )
    p.add_argument("--label", default="", help="--stage-report: the column label of this run")
    p.add_argument("--no-progress", action="store_true")
    p.add_argument(
        "--tensorboard",
        default="",
        help="TensorBoard event files of the campaign's scalars in this folder (default: "
        "tensorboard/NAME beside the store; docs/agent.md)",
    )
    p.add_argument("--no-tensorboard", action="store_true", help="write no TensorBoard event files")
    a = p.parse_args(argv)
    if a.scenarios < 1:
        p.error("--scenarios must be >= 1")
    if a.reward == "differential" and not a.reference_workers:
        p.error("--reward differential needs --reference-workers (the reference stack to subtract)")
    if not (math.isfinite(a.collision_bonus) and a.collision_bonus >= 0.0):
        p.error(f"--collision-bonus {a.collision_bonus}: must be a finite number >= 0")
    return a


def worker_names(spec: str):
    if spec.isdigit():
        n = int(spec)
        if n < 1:
            raise ValueError("--workers must be >= 1")
        return [f"/worker_{i}" for i in range(n)]
    return ["/" + s.strip().strip("/") for s in spec.split(",") if s.strip()]


def print_summary(store, name, out=sys.stdout):
    s = store.summary(name)
    best = "n/a" if s["max_proxy"] is None else f"{s['max_proxy']:.3f}"
    print(
        f"\ncampaign {name}: {s['scenarios']} scenarios, proxy >= 3: {s['proxy_ge_3']}, "
        f">= 4: {s['proxy_ge_4']}, largest proxy {best}",
        file=out,
    )
    print("terminations: " + ", ".join(f"{k} {v}" for k, v in sorted(s["terminations"].items())), file=out)
    if s["attributed"]:
        print(
            f"attribution ({s['attributed']} scenarios re-run on the reference stack): of the proxy >= 3, "
            f"{s['perception_ge3']} are the perception's (reference < 2), {s['stack_ge3']} the stack's "
            f"(reference >= 3); proxy - reference >= 1: {s['differential_ge1']}",
            file=out,
        )
        print(
            f"collisions: {s['perception_collisions']} the perception's (the reference stack drove through), "
            f"{s['stack_collisions']} the stack's (the reference collided too)",
            file=out,
        )
    if s["plr_below_0999"]:
        print(
            f"warning: {s['plr_below_0999']} runs reached the goal with PLR < 0.999 (the optimal path overestimated)",
            file=out,
        )
    print("top 10 (store row id, job, episode.step, proxy = 0.1 vis + yaw term + PLR^2):", file=out)
    for r in s["top"]:
        print(
            f"  id {r['id']:>6}  job {r['job']:>5}  ep {r['episode']}.{r['step']}  proxy {r['proxy']:.3f}  "
            f"(vis {r['vis']:+.2f}, yaw {r['yaw_term']:.3f}, PLR {r['plr']:.3f}, {r['termination']})",
            file=out,
        )
    print(f"store: {os.path.abspath(store.path)}", file=out)
    return s


def write_stage_report(a, c, store, name, collector, workers, t_wall, t_cpu):
    from asg_agent.analysis.bench import breakdown

    wall, cpu = time.time() - t_wall, time.process_time() - t_cpu
    first, last = {}, {}
    if collector is not None:
        time.sleep(1.5)  # the nodes publish their readings at most once a second
        first, last = collector.snapshot()
    rows = [r for r in store.rows(name) if r["finished"] >= t_wall]
    sim = sum(r["sim_time"] or 0.0 for r in rows)
    agent = {"seconds": c.stages.seconds, "calls": c.stages.calls, "cpu": cpu}
    try:
        out = breakdown(first, last, agent, len(rows), wall, sim, workers)
    except ValueError as e:
        print(f"campaign: --stage-report: {e}", file=sys.stderr)
        return
    out.update(label=a.label or f"{workers} worker(s)", campaign=name, method=c.method.name, experiment=c.exp.name)
    os.makedirs(os.path.dirname(os.path.abspath(a.stage_report)), exist_ok=True)
    with open(a.stage_report, "w") as f:
        json.dump(out, f, indent=1, sort_keys=True)
    print(f"stage report: {a.stage_report} ({out['rate_per_hour']:.0f} scenarios an hour)", file=sys.stderr)


def main(argv=None):
    # roslaunch adds remappings (__name:=..., __log:=...): not ours to parse.
    a = parse([x for x in sys.argv[1:] if ":=" not in x] if argv is None else argv)
    try:
        exp = load_experiment(a.experiment)
    except ExperimentError as e:
        print(f"campaign: {e}", file=sys.stderr)
        return 2
    name = a.name or f"{exp.name}-{a.method}-s{a.seed}"
    try:
        workers = [f"fake_{i}" for i in range(a.fake_workers)] if a.fake_workers else worker_names(a.workers)
    except ValueError as e:
        print(f"campaign: {e}", file=sys.stderr)
        return 2
    ref_workers = []
    if a.reference_workers:
        spec = a.reference_workers
        if spec.isdigit():
            first = len(workers)
            ref_workers = (
                [f"fake_ref_{i}" for i in range(int(spec))]
                if a.fake_workers
                else [f"/worker_{first + i}" for i in range(int(spec))]
            )
        else:
            ref_workers = worker_names(spec)
        if not ref_workers or set(ref_workers) & set(workers):
            print("campaign: --reference-workers must name workers other than --workers", file=sys.stderr)
            return 2
    slots = a.slots or 2 * len(workers)
    try:
        os.makedirs(os.path.dirname(os.path.abspath(a.store)), exist_ok=True)
        store = Store(a.store)
    except OSError as e:
        print(f"campaign: --store {a.store}: cannot create its folder ({e.strerror})", file=sys.stderr)
        return 2
    except StoreError as e:
        print(f"campaign: {e}", file=sys.stderr)
        return 2
    if not a.resume and store.campaign(name) is not None:
        print(
            f"campaign: {name!r} already exists in {a.store}: add --resume to continue it, or --name", file=sys.stderr
        )
        return 2
    reference = None
    if a.fake_workers:
        from asg_agent.campaign.fake_pool import FakePool

        pool = FakePool(a.fake_workers, seed=int(time.time()))
        if ref_workers:  # a stand-in reference stack that wiggles less
            reference = FakePool(len(ref_workers), seed=int(time.time()) + 1, gain=0.3, prefix="fake_ref")
    else:
        import rospy
        from asg_agent.ros.pool import WorkerPool

        rospy.init_node("campaign", anonymous=True, disable_signals=True)
        try:
            pool = WorkerPool(workers, answer_timeout=a.answer_timeout)
            if ref_workers:
                reference = WorkerPool(ref_workers, answer_timeout=a.answer_timeout)
        except RuntimeError as e:
            print(f"campaign: {e}", file=sys.stderr)
            return 2
        # The planner is part of the stack's identity: every worker must run the experiment's
        # configuration (e.g. exp6's planner_terrain.yaml, not the flat planner.yaml).
        from asg_agent.ros.replay import planner_mismatch

        wrong = [m for w in list(workers) + list(ref_workers) for m in planner_mismatch(w, exp.planner_config)]
        if wrong:
            print(
                f"campaign: the experiment's planner_config is {exp.planner_config}, but:\n  "
                + "\n  ".join(wrong[:8])
                + "\n(launch the workers with planner_config:=... of that file)",
                file=sys.stderr,
            )
            return 2
    td3 = TD3Config()
    if a.updates_per_step:
        td3.updates_per_step = a.updates_per_step
    td3.bc_weight = a.bc_weight
    method = make_method(a.method, exp, a.seed, budget=a.scenarios, td3_config=td3)
    checkpoint = checkpoint_path(a.store, name)
    bar = None
    if not a.no_progress:
        from tqdm import tqdm

        bar = tqdm(total=a.scenarios, unit="scn", dynamic_ncols=True, file=sys.stderr)

    def progress(st):
        if bar is None:
            return
        bar.n = st["done"]
        best = "-" if not math.isfinite(st["best"]) else f"{st['best']:.2f}"
        diff = ""
        if st.get("perception") is not None:
            diff = f" perception {st['perception']} stack {st['stack']}"
        if st.get("diff_best") is not None and math.isfinite(st["diff_best"]):
            diff += f" diff best {st['diff_best']:+.2f} >=1 {st['diff_ge1']}"
        bar.set_postfix_str(
            f"{st['rate_per_hour']:.0f}/h best {best} >=3 {st['ge3']} >=4 {st['ge4']}{diff}"
            + (f" err {st['errors']}" if st["errors"] else ""),
            refresh=True,
        )

    settings = {
        "workers": workers,
        "reference_workers": ref_workers,
        "reward": a.reward,
        **({"collision_bonus": a.collision_bonus} if a.reward == "collision" else {}),
        "experiment_file": exp.source,
        "perception": exp.perception,
        "model": exp.model,
        "unet_backend": exp.unet_backend,
        "planner_config": exp.planner_config,
        "fake": bool(a.fake_workers),
    }
    if not a.fake_workers:
        # The stack identity stored with the campaign must be what the workers run (issue #24:
        # a backend left at another value than the experiment's would be recorded falsely).
        from asg_agent.ros.replay import stack_mismatch

        wrong = [m for w in workers for m in stack_mismatch(w, settings)]
        if wrong:
            print(
                "campaign: the workers do not run the experiment's stack (" + exp.source + "): " + "; ".join(wrong),
                file=sys.stderr,
            )
            return 2
    collector = None
    if a.stage_report and not a.fake_workers:
        from asg_agent.ros.stages import StageCollector

        collector = StageCollector(workers)
        nodes = 3 if exp.perception == "unet" else 2
        if not collector.wait_for(nodes * len(workers), timeout=15.0):
            print(
                "campaign: --stage-report: not every worker, segmenter and planner published stage_times "
                "within 15 s; the breakdown will lack them",
                file=sys.stderr,
            )
    c = Campaign(
        name,
        exp,
        method,
        store,
        pool,
        a.scenarios,
        a.seed,
        checkpoint,
        slots=slots,
        checkpoint_every=a.checkpoint_every,
        progress=progress,
        settings=settings,
        early_dispatch=not a.no_early_dispatch,
        reference=reference,
        reward=a.reward,
        collision_bonus=a.collision_bonus,
    )
    tb = None
    try:
        if a.resume and store.campaign(name) is None:
            # Killed before it stored anything: "--resume" then means "start it" (restarts stay
            # one command, whenever the kill came).
            print(f"campaign {name}: nothing stored yet, starting it", file=sys.stderr)
            c.start()
        elif a.resume:
            c.resume()
            print(
                f"campaign {name}: resumed with {store.count(name)} of {a.scenarios} scenarios stored", file=sys.stderr
            )
        else:
            c.start()
        tb = None if a.no_tensorboard else open_tensorboard(a, store, name, c)
        if tb:
            c.scalars = tb.scenario
        progress(c.status())
        t_wall, t_cpu = time.time(), time.process_time()
        c.run()
        if a.stage_report:
            write_stage_report(a, c, store, name, collector, len(workers), t_wall, t_cpu)
    except (ValueError, StoreError) as e:
        print(f"campaign: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        if bar:
            bar.close()
        if tb:
            tb.close()
        print(f"\ncampaign {name}: interrupted; `--resume` continues it", file=sys.stderr)
        return 130
    if bar:
        bar.close()
    if tb:
        tb.close()
        print(f"tensorboard: {tb.logdir} (tensorboard --logdir {os.path.dirname(tb.logdir)})")
    print_summary(store, name)
    print(f"checkpoint: {checkpoint}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
