"""campaign: run (or resume) a scene-generation campaign against running scene workers.

    campaign EXPERIMENT.yaml [--method td3-per-asp] [--scenarios 500] [--workers 2]
             [--store results/campaigns.sqlite] [--name NAME] [--seed 0] [--resume]

Workers are the namespaces /worker_0 .. /worker_{N-1} (or a comma-separated list of
namespaces), started by `roslaunch launch/worker.launch ns:=worker_i ...` on this host or any
other host of the same ROS master, or by launch/train.launch (the tests hand main() the workers
of their in-process stand-in instead). Prints a progress bar and ends with a summary: the findings of its reward, their distinct places and the replay
command of the best of them first (issue #78), then the attribution and the paper's proxy counts.
"""

import argparse
import json
import math
import os
import sys
import time

from asg_agent.blas import blas_identity, pin_blas

pin_blas()  # before numpy and torch load OpenBLAS: the same kernel on every CPU (asg_agent/blas.py)

from asg_agent.campaign.config import CampaignConfig, FunctionCallback  # noqa: E402
from asg_agent.campaign.loop import Campaign  # noqa: E402
from asg_agent.campaign.policy import CANDIDATE_RULES  # noqa: E402
from asg_agent.scoring.rewards import REWARDS  # noqa: E402
from asg_agent.campaign.policy import CampaignError, campaign_settings, reference_roles  # noqa: E402
from asg_agent.ros.campaign_pools import RosWorkers  # noqa: E402
from asg_agent.cli.signals import stop_on_signals  # noqa: E402
from asg_agent.scoring import attribution as attr  # noqa: E402
from asg_agent.scoring import rewards  # noqa: E402
from asg_agent.records.experiment import ExperimentError, load_experiment  # noqa: E402
from asg_agent.search.methods import METHODS, make_method  # noqa: E402
from asg_agent.search.coverage import GENERATORS  # noqa: E402
from asg_agent import defaults  # noqa: E402
from asg_agent.paths import REPO  # noqa: E402
from asg_agent.records.store import Store, StoreError, checkpoint_path  # noqa: E402
from asg_agent.search.td3 import TD3Config  # noqa: E402


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


def parse(argv, options=None):
    """The parsed arguments; `options(parser)` adds the workers' own (see main's `workers`)."""
    p = argparse.ArgumentParser(prog="campaign", description=__doc__.split("\n\n")[0])
    _search_options(p)
    _run_options(p)
    if options is not None:
        options(p)
    a = p.parse_args(argv)
    _check(p, a)
    return a


def _search_options(p):
    """What runs: the experiment, the search, its budget and seed, the workers and the store."""
    D = defaults.DEFAULTS
    p.add_argument(
        "experiment",
        nargs="?",
        default=os.path.join(REPO, D["experiment"].value),
        help=f"experiment file (default {defaults.text('experiment')}, train.launch's; asg_agent/defaults.py)",
    )
    p.add_argument("--method", default=D["method"].value, choices=METHODS, help=f"(default {D['method'].value})")
    p.add_argument(
        "--scenarios",
        type=int,
        default=D["scenarios"].value,
        help=f"scenarios to run in all (default {D['scenarios'].value})",
    )
    p.add_argument(
        "--workers",
        default=str(D["workers"].value),
        help=f"worker count N (/worker_0..N-1) or namespaces, comma-separated (default {D['workers'].value})",
    )
    p.add_argument(
        "--store",
        default=os.path.expanduser(D["store"].value),
        help=f"SQLite scenario store (default {D['store'].value}, train.launch's)",
    )
    p.add_argument("--name", default="", help="campaign name (default: EXPERIMENT-METHOD-sSEED)")
    p.add_argument("--seed", type=int, default=D["seed"].value, help=f"(default {D['seed'].value})")
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
        default=TD3Config.bc_weight,
        help=f"TD3 methods: weight of the behaviour-regularisation term (default {TD3Config.bc_weight:g}, the "
        "setting of every documented campaign; 0: off, the variant that collapses to the border)",
    )
    p.add_argument(
        "--route-band",
        type=float,
        default=D["route_band"].value,
        help=f"[m] route-random: half-width of the band around the straight start-goal route "
        f"(default {defaults.text('route_band')})",
    )
    p.add_argument(
        "--route-share",
        type=float,
        default=1.0,
        help="[-] route-random: the share of obstacles placed in the band, the rest anywhere (default 1)",
    )
    p.add_argument(
        "--tabu-m",
        type=float,
        default=D["tabu_m"].value,
        help=f"[m] novelty-ts: no proposal puts an obstacle this close to a found failure's place of its "
        f"class (default {defaults.text('tabu_m')}, protocol v4's distinct radius)",
    )
    p.add_argument(
        "--generators",
        *D["generators"].aliases,
        dest="generators",
        default=D["generators"].value,
        help=f"coverage-ts, coverage-veto: its generators, comma-separated, some of {', '.join(GENERATORS)} "
        f"(default {D['generators'].value}; docs/agent.md)",
    )
    p.add_argument(
        "--atlas",
        default=D["atlas"].value,
        help="the failure atlas whose places the progress bar, TensorBoard and the summary count as "
        "covered (rosrun asg_agent atlas; docs/agent.md): a file, `auto` (the one of "
        "results/atlas/ whose scene, stack and finding kind are the campaign's, if any) or `none` (default "
        f"{D['atlas'].value})",
    )
    p.add_argument(
        "--rule",
        default="",
        help="rule-sampler: the rule file (JSON; asg_analysis.rules writes them) whose layouts it draws",
    )


def _run_options(p):
    """How it runs: references and attribution, the reward, reports and outputs."""
    p.add_argument(
        "--reference-workers",
        default="",
        help="attribution: every scenario also runs on these workers (count, as --workers, "
        "numbered after them, or namespaces), the reference stack (ground-truth labels, "
        "the same planner and follower); each finding is counted as the perception's "
        "(reference proxy < 2) or the stack's (reference proxy >= 3)",
    )
    p.add_argument(
        "--reference",
        action="append",
        default=[],
        metavar="ROLE=WORKERS",
        help="three-stack attribution (issue #36): a reference stack by role, full (the unflawed U-Net "
        "on the same backend) or ground_truth, and its workers (count, numbered after the workers "
        "before it, or namespaces); give both. Candidates (--candidates) are re-run on each, and "
        "every candidate is classed flaw, model, stack, unclear, reverse, pass or error (docs/agent.md). "
        "Any stack pair (issue #67): release (the registration the stack under test names as its reference, "
        "e.g. its last release) alone, and each candidate is classed regression, shared, unclear, reverse, "
        "pass or error",
    )
    p.add_argument(
        "--candidates",
        default="",
        choices=("",) + CANDIDATE_RULES,
        help="which scenarios run on the references: failures (a collision, timeout, flip, out of "
        "bounds, or proxy >= 2: the default with --reference) or all (the default with "
        "--reference-workers)",
    )
    p.add_argument(
        "--full-model",
        default="",
        help="--reference full: the unflawed model its workers must run (default: the experiment's "
        "model with 'flawed' read as 'full')",
    )
    p.add_argument(
        "--reward",
        default=defaults.DEFAULTS["reward"].value,
        choices=REWARDS + (rewards.AUTO,),
        help="what the search maximises: auto (the one the references can see: flaw with --reference "
        "full=..., regression with --reference release=..., else failure; train.launch's default), the stack under test's proxy (the paper), "
        "proxy - reference proxy (differential; needs --reference-workers), the proxy plus "
        "--collision-bonus when the stack under test collided and the reference reached the goal (collision), "
        "the proxy plus a dense term for how close the vehicle came to an obstacle (clearance) or how soon it "
        "would have hit one (ttc), or the proxy and clearance lost against the unflawed stack (regret; needs "
        "--reference full=... and --candidates all), or the injected flaw itself: 1 for a flaw finding, a "
        "graded part below 0.5 for a candidate the unflawed stack drove clear, 0 otherwise (flaw; needs "
        "--reference full=... ground_truth=...); scoring/rewards.py",
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


def _check(p, a):
    """Options that do not fit together: p.error naming them."""
    if a.scenarios < 1:
        p.error("--scenarios must be >= 1")
    if a.reward == rewards.AUTO:  # stored as what it stands for: the campaign's record names its reward
        a.reward = rewards.for_roles([r.partition("=")[0] for r in a.reference])
    if a.reward == "regret" and not (any(r.startswith("full=") for r in a.reference) and a.candidates == "all"):
        p.error("--reward regret needs --reference full=WORKERS (and ground_truth) with --candidates all")
    if a.reward == "flaw" and not any(r.startswith("full=") for r in a.reference):
        p.error("--reward flaw needs --reference full=WORKERS and ground_truth=WORKERS (attribution:=three)")
    if a.reward == "differential" and not (a.reference_workers or a.reference):
        p.error("--reward differential needs --reference-workers (the reference stack to subtract)")
    if a.reference and a.reference_workers:
        p.error("give --reference ROLE=WORKERS (named references) or --reference-workers (ground truth), not both")
    roles = [r.partition("=")[0] for r in a.reference]
    for r in a.reference:
        role, eq, spec = r.partition("=")
        if not eq or not spec or role not in attr.ROLES:
            p.error(f"--reference {r!r}: must be ROLE=WORKERS with ROLE one of {', '.join(attr.ROLES)}")
    if len(set(roles)) != len(roles):
        p.error(f"--reference: each role once (got {', '.join(roles)})")
    if a.reference and attr.TRUTH not in roles and attr.RELEASE not in roles:
        p.error(
            f"--reference: attribution needs a {attr.TRUTH} reference (the simulator's labels), or a "
            f"{attr.RELEASE} reference for a stack pair"
        )
    if a.reward == "regression" and attr.RELEASE not in roles:
        p.error("--reward regression needs --reference release=WORKERS (attribution:=release)")
    if not (math.isfinite(a.collision_bonus) and a.collision_bonus >= 0.0):
        p.error(f"--collision-bonus {a.collision_bonus}: must be a finite number >= 0")


def generator_line(camp) -> str:
    """The summary's line naming the scene generator that ran (issue #54: `bash scripts/train.sh`
    runs the flaw study's winner; the others are one argument away): method, its settings, the
    reward and the experiment file."""
    settings = json.loads(camp["settings"]) if camp and camp["settings"] else {}
    # the settings that say what a method samples (route-random's band); a learner's hyperparameters
    # are in the store's settings and docs/agent.md, not in one line
    config = {k: v for k, v in (settings.get("method_config") or {}).items() if k in ("band", "share", "tabu_m")}
    what = ", ".join(
        f"{k} {v:g}{' m' if k in ('band', 'tabu_m') else ''}" if isinstance(v, float) else f"{k} {v}"
        for k, v in sorted(config.items())
    )
    exp = settings.get("experiment_repo_file") or settings.get("experiment_file") or camp["experiment"]
    return (
        f"scene generator: {camp['method']}{f' ({what})' if what else ''}, reward {settings.get('reward', 'proxy')}, "
        f"experiment {exp}, seed {camp['seed']}"
    )


def stack_line(camp) -> str:
    """The summary's line naming the stack under test and its numerics (issue #53); for bf16, the
    fast mode, that its findings replay only where oneDNN runs the recorded ISA."""
    settings = json.loads(camp["settings"]) if camp and camp["settings"] else {}
    if settings.get("stack", "paper") != "paper" or settings.get("perception") != "unet":
        return f"stack under test: {settings.get('stack', 'paper')}, perception {settings.get('perception', '?')}"
    numerics = settings.get("numerics") or settings.get("unet_backend", "?")
    line = f"stack under test: U-Net {settings.get('model')} ({numerics}), planner {settings.get('planner_config')}"
    from asg_perception.numerics import BF16_BACKENDS

    if numerics.split()[0] in BF16_BACKENDS:
        isa = dict(kv.split("=", 1) for kv in numerics.split()[1:] if "=" in kv).get("isa", "?")
        line += (
            f"\nbf16 fast mode: these findings replay bit for bit only where oneDNN runs {isa}; elsewhere "
            f"`replay` refuses them and reruns each on the default numerics on request"
        )
    return line


def campaign_atlas(choice: str, exp, settings: dict):
    """The failure atlas (scoring.atlas.Atlas) a campaign counts its coverage of, recorded in
    `settings["atlas"]`: the file `choice`, or with `auto` the one of the repository's
    results/atlas/ of the campaign's identity (records/atlas.py), or None (`none`, or `auto` with no
    such file, or a reward whose findings no atlas pools). CampaignError naming what does not fit."""
    from asg_agent.paths import REPO, repo_relative
    from asg_agent.records import atlas as ra
    from asg_agent.scoring import atlas as sa

    if choice == "none":
        return None
    kind = settings.get("reward")
    if kind not in sa.KINDS:
        if choice == "auto":
            return None
        raise CampaignError(f"--atlas {choice}: an atlas pools {', '.join(sa.KINDS)} findings, not the {kind} reward's")
    ident = ra.identity({"name": exp.name, "settings": json.dumps(settings), "experiment_text": exp.text}, kind)
    if choice == "auto":
        found = ra.matching(os.path.join(REPO, "results", "atlas"), ident)
        if not found:
            return None
        choice = found[0]
    try:
        d = ra.read(choice)
    except ValueError as e:
        raise CampaignError(f"--atlas: {e}") from None
    diff = sa.same_identity(d["identity"], ident)
    if diff:
        raise CampaignError(
            f"--atlas {choice}: its "
            + ", ".join(f"{k} {d['identity'].get(k)!r}" for k in diff)
            + " differ from the campaign's ("
            + ", ".join(f"{ident.get(k)!r}" for k in diff)
            + ")"
        )
    atlas = sa.load(choice)
    # the places themselves: the file grows by versions, and the summary (and any analysis of the
    # export) recounts against the atlas the campaign counted live
    settings["atlas"] = {
        "file": repo_relative(choice) or os.path.abspath(choice),
        "version": d["version"],
        "radius_m": atlas.radius,
        "places": [[p["cls"], p["x"], p["y"]] for p in atlas.places],
    }
    return atlas


def coverage_line(settings: dict, found) -> str:
    """The summary's coverage line of a campaign's findings `found` (campaign/findings.py), counted
    again from the store (not the live tally) against the atlas's places as the campaign recorded
    them; "" without an atlas."""
    from asg_agent.scoring import atlas as sa

    rec = settings.get("atlas")
    if not rec:
        return ""
    places = [{"cls": c, "x": x, "y": y, "findings": 0} for c, x, y in rec["places"]]
    cov = sa.Coverage(sa.Atlas(places, rec["radius_m"]))
    for f in found:
        cov.add(tuple(f["place"]))
    return (
        f"coverage of the failure atlas {rec['file']} (v{rec['version']}; a place is covered by a finding of its "
        f"class within {rec['radius_m']:g} m): {sa.coverage_text(cov.counts())}, recall {cov.recall():.2f}"
    )


def findings_lines(store, name, top: int = 10) -> list:
    """The summary's first lines (issue #78): the campaign's findings, their distinct places at
    each reported radius, by class, and the first finding of each distinct place with its replay
    command, largest reward first."""
    from asg_agent.campaign.findings import distinct_summary, findings, finding_rule

    camp = store.campaign(name)
    settings = json.loads(camp["settings"]) if camp and camp["settings"] else {}
    rule = finding_rule(settings)
    found = findings(store, name)
    d = distinct_summary(found)
    radii = sorted(d["distinct"])
    primary = d["primary_radius_m"]
    others = ", ".join(f"{d['distinct'][r]} at {r:g} m" for r in radii if r != primary)
    lines = [
        f"\ncampaign {name}: {store.count(name)} scenarios, {d['findings']} findings of the {rule.name} reward "
        f"(reward >= {rule.finding_at:g}), {d['distinct'][primary]} distinct at {primary:g} m ({others}): "
        "a finding is distinct when the obstacle it hit (or, without contact, where it ended) lies at "
        f"least {primary:g} m from every earlier distinct one of its class",
    ]
    cov = coverage_line(settings, found)
    if cov:
        lines.append(cov)
    if d["by_class"]:
        lines.append("findings by what they hit: " + ", ".join(f"{k} {v}" for k, v in d["by_class"].items()))
    first = sorted(d["first_at_each_place"], key=lambda f: (-f["reward"], f["job"]))[:top]
    if first:
        lines.append(
            f"best distinct findings (the first at each place; replay: rosrun asg_agent replay STORE {name} JOB):"
        )
    for f in first:
        cls, x, y = f["place"]
        what = f"{cls} at ({x:.1f}, {y:.1f}) m" if cls != "no contact" else f"no contact, ended at ({x:.1f}, {y:.1f}) m"
        lines.append(
            f"  job {f['job']:>5}  {f['termination']:<13} {what}"
            + (f"  {f['attribution']}" if f["attribution"] else "")
            + f"  reward {f['reward']:.3f}  ->  rosrun asg_agent replay {os.path.abspath(store.path)} {name} {f['job']}"
        )
    return lines


def print_summary(store, name, out=sys.stdout):
    s = store.summary(name)
    for line in findings_lines(store, name):
        print(line, file=out)
    print(generator_line(store.campaign(name)), file=out)
    print(stack_line(store.campaign(name)), file=out)
    cl = s["classes"]
    refs = (
        (json.loads(store.campaign(name)["settings"] or "{}").get("references") or {}) if store.campaign(name) else {}
    )
    if sum(cl.values()) and attr.RELEASE in refs and attr.TRUTH not in refs:
        rerun = sum(v for k, v in cl.items() if k != attr.NOT_CANDIDATE)
        print(
            f"stack-pair attribution against {refs[attr.RELEASE].get('stack', 'the release')} ({rerun} of "
            f"{s['scenarios']} scenarios re-run on it, {cl[attr.NOT_CANDIDATE]} not candidates): regression "
            f"{cl['regression']}, shared {cl['shared']}; unclear {cl['unclear']}, reverse {cl['reverse']}, "
            f"pass {cl['pass']}, error {cl['error']}" + (f", pending {cl[attr.PENDING]}" if cl[attr.PENDING] else ""),
            file=out,
        )
    elif sum(cl.values()):
        rerun = sum(v for k, v in cl.items() if k != attr.NOT_CANDIDATE)
        print(
            f"three-stack attribution ({rerun} of {s['scenarios']} scenarios re-run on the references, "
            f"{cl[attr.NOT_CANDIDATE]} not candidates): flaw {cl['flaw']}, model {cl['model']}, stack {cl['stack']}"
            + (f", perception {cl['perception']}" if cl["perception"] else "")
            + f"; unclear {cl['unclear']}, reverse {cl['reverse']}, pass {cl['pass']}, error {cl['error']}"
            + (f", pending {cl[attr.PENDING]}" if cl[attr.PENDING] else ""),
            file=out,
        )
    # the paper's proxy after what the campaign searched for and the attribution (issue #95)
    print("terminations: " + ", ".join(f"{k} {v}" for k, v in sorted(s["terminations"].items())), file=out)
    best = "n/a" if s["max_proxy"] is None else f"{s['max_proxy']:.3f}"
    print(
        f"the paper's proxy: >= 3 in {s['proxy_ge_3']}, >= 4 in {s['proxy_ge_4']}, largest {best}",
        file=out,
    )
    if s["attributed"]:
        print(
            f"the proxy against the reference ({s['attributed']} scenarios re-run on it): of the proxy >= 3, "
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
    reward = (json.loads(store.campaign(name)["settings"] or "{}") if store.campaign(name) else {}).get("reward")
    if reward in (None, "proxy"):  # the proxy's top 10 belongs to a search on the proxy
        print("top 10 (store row id, job, episode.step, proxy = 0.1 vis + yaw term + PLR^2):", file=out)
    for r in s["top"] if reward in (None, "proxy") else ():
        print(
            f"  id {r['id']:>6}  job {r['job']:>5}  ep {r['episode']}.{r['step']}  proxy {r['proxy']:.3f}  "
            f"(vis {r['vis']:+.2f}, yaw {r['yaw_term']:.3f}, PLR {r['plr']:.3f}, {r['termination']})",
            file=out,
        )
    print(f"store: {os.path.abspath(store.path)}", file=out)
    return s


def write_stage_report(a, c, store, name, collector, workers, t_wall, t_cpu, groups=None):
    from asg_agent.records.stage_costs import breakdown, stack_costs

    wall, cpu = time.time() - t_wall, time.process_time() - t_cpu
    first, last = {}, {}
    if collector is not None:
        time.sleep(1.5)  # the nodes publish their readings at most once a second
        first, last = collector.snapshot()
    rows = [r for r in store.rows(name) if r["finished"] >= t_wall]
    sim = sum(r["sim_time"] or 0.0 for r in rows)
    agent = {"seconds": c.stages.seconds, "calls": c.stages.calls, "cpu": cpu}
    groups = groups or {}
    tested = set(groups.get("under test", ()))
    try:
        out = breakdown(
            {k: v for k, v in first.items() if not tested or k[0] in tested},
            {k: v for k, v in last.items() if not tested or k[0] in tested},
            agent,
            len(rows),
            wall,
            sim,
            workers,
        )
        if groups:
            out["stacks"] = stack_costs(first, last, groups, len(rows))
            labels = [r["attribution"] for r in rows]
            if any(labels):
                out["rerun_share"] = sum(x not in (None, attr.NOT_CANDIDATE) for x in labels) / len(rows)
    except ValueError as e:
        print(f"campaign: --stage-report: {e}", file=sys.stderr)
        return
    out.update(label=a.label or f"{workers} worker(s)", campaign=name, method=c.method.name, experiment=c.exp.name)
    os.makedirs(os.path.dirname(os.path.abspath(a.stage_report)), exist_ok=True)
    with open(a.stage_report, "w") as f:
        json.dump(out, f, indent=1, sort_keys=True)
    print(f"stage report: {a.stage_report} ({out['rate_per_hour']:.0f} scenarios an hour)", file=sys.stderr)


def open_store(a, name: str) -> Store:
    try:
        os.makedirs(os.path.dirname(os.path.abspath(a.store)), exist_ok=True)
        store = Store(a.store)
    except OSError as e:
        raise CampaignError(f"--store {a.store}: cannot create its folder ({e.strerror})") from e
    except StoreError as e:
        raise CampaignError(str(e)) from e
    if not a.resume and store.campaign(name) is not None:
        raise CampaignError(f"{name!r} already exists in {a.store}: add --resume to continue it, or --name")
    return store


#: the options each method takes from the campaign's arguments: {its argument: the argument (dest)}
OPTIONS = {
    "route-random": {"band": "route_band", "share": "route_share"},
    "novelty-ts": {"tabu_m": "tabu_m"},
    "coverage-ts": {"generators": "generators"},
    "coverage-veto": {"generators": "generators"},
    "rule-sampler": {"rule_file": "rule"},
}


def make_search(a, exp):
    td3 = TD3Config()
    if a.updates_per_step:
        td3.updates_per_step = a.updates_per_step
    td3.bc_weight = a.bc_weight
    options = {opt: getattr(a, dest) for opt, dest in OPTIONS.get(a.method, {}).items()}
    try:
        return make_method(a.method, exp, a.seed, budget=a.scenarios, td3_config=td3, options=options)
    except ValueError as e:
        raise CampaignError(str(e)) from e


#: the most fields the progress bar shows (docs/agent.md, "What a campaign prints")
BAR_FIELDS = 6


def bar_fields(st: dict) -> list:
    """The progress bar's fields from Campaign.status(), at most BAR_FIELDS: the findings of the
    campaign's reward, named (`flaw findings 3`), how many are distinct (`distinct 2 (2 m)`), the
    atlas's places covered where there is an atlas (`covered 4/67`), the rate with the errors
    (`1369/h`, `1369/h 2 err`), the re-runs on the reference stacks where there are any
    (`rerun 6`), and only where the reward is the paper's proxy, its best (`best proxy 3.37`) or,
    for the differential reward, the best difference."""
    out = [f"{st['reward']} findings {st['findings']}", f"distinct {st['distinct']} ({st['distinct_radius_m']:g} m)"]
    cov = st.get("coverage")
    if cov:
        out.append(f"covered {cov['covered']}/{cov['known']}")
    out.append(f"{st['rate_per_hour']:.0f}/h" + (f" {st['errors']} err" if st["errors"] else ""))
    cl = st.get("classes")
    if cl and (attr.FULL in st.get("roles", ()) or attr.RELEASE in st.get("roles", ())):
        out.append(f"rerun {sum(v for k, v in cl.items() if k != attr.NOT_CANDIDATE)}")
    if st["reward"] == "differential" and st.get("diff_best") is not None and math.isfinite(st["diff_best"]):
        out.append(f"best diff {st['diff_best']:+.2f}")
    elif st["reward"] == "proxy" and math.isfinite(st["best"]):
        out.append(f"best proxy {st['best']:.2f}")
    return out[:BAR_FIELDS]


def bar_text(st: dict) -> str:
    """The progress bar's text: its fields (bar_fields), two spaces apart."""
    return "  ".join(bar_fields(st))


def progress_bar(a):
    """(bar, progress callback): a tqdm bar on stderr, or none with --no-progress."""
    bar = None
    if not a.no_progress:
        from tqdm import tqdm

        bar = tqdm(total=a.scenarios, unit="scn", dynamic_ncols=True, file=sys.stderr)

    def progress(st):
        if bar is None:
            return
        bar.n = st["done"]
        bar.set_postfix_str(bar_text(st), refresh=True)

    return bar, progress


def run(a, c: Campaign, store: Store, name: str, bar, progress, collector, workers, roles) -> int:
    """Starts or resumes the campaign and runs it to its budget; the summary at the end."""
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
            c.add_callback(tb)
        progress(c.status())
        t_wall, t_cpu = time.time(), time.process_time()
        c.run()
        if a.stage_report:
            groups = {"under test": list(workers), **roles}
            write_stage_report(a, c, store, name, collector, len(workers), t_wall, t_cpu, groups)
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
    print(f"checkpoint: {c.checkpoint_path}")
    return 0


def main(argv=None, workers=None):
    """`workers`: what runs the scenarios (default RosWorkers(), the scene workers of the ROS master;
    the tests pass their in-process stand-in's). It adds its options to the parser (`options(p)`),
    names the workers under test (`names(a)`) and a reference role's counted ones (`numbered(role,
    first, n)`), makes the pools (`pools(a, exp, workers, roles)` -> (pool, {role: pool})), checks
    that they run the experiment's stack (`check(exp, settings, workers, roles)`), gives the
    --stage-report collector (`collector(a, exp, settings, workers, roles)`, or None) and what the
    store records of it beside the campaign's settings (`settings`)."""
    workers_of = workers or RosWorkers()
    a = parse([x for x in sys.argv[1:] if ":=" not in x] if argv is None else argv, workers_of.options)
    stop_on_signals()
    try:
        exp = load_experiment(a.experiment)
        name = a.name or f"{exp.name}-{a.method}-s{a.seed}"
        workers = workers_of.names(a)
        roles = reference_roles(a, workers, workers_of.numbered)
        candidates = a.candidates or ("all" if a.reference_workers else "failures")
        store = open_store(a, name)
        pool, references = workers_of.pools(a, exp, workers, roles)
        method = make_search(a, exp)
        settings = {**campaign_settings(a, exp, workers, roles, candidates), **workers_of.settings}
        settings["agent_blas"] = blas_identity()  # the search's arithmetic (asg_agent/blas.py)
        atlas = campaign_atlas(a.atlas, exp, settings)
        workers_of.check(exp, settings, workers, roles)
    except (ExperimentError, ValueError, CampaignError) as e:
        print(f"campaign: {e}", file=sys.stderr)
        return 2
    bar, progress = progress_bar(a)
    collector = workers_of.collector(a, exp, settings, workers, roles)
    c = Campaign(
        CampaignConfig(
            name=name,
            experiment=exp,
            method=method,
            store=store,
            pool=pool,
            total=a.scenarios,
            seed=a.seed,
            checkpoint=checkpoint_path(a.store, name),
            slots=a.slots or 2 * len(workers),
            checkpoint_every=a.checkpoint_every,
            settings=settings,
            early_dispatch=not a.no_early_dispatch,
            references=references,
            candidates=candidates if references else None,
            reward=a.reward,
            collision_bonus=a.collision_bonus,
            callbacks=[FunctionCallback(progress=progress)],
            atlas=atlas,
        )
    )
    return run(a, c, store, name, bar, progress, collector, workers, roles)


if __name__ == "__main__":
    sys.exit(main())
