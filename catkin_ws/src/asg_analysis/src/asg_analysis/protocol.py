"""A study fixed before its data (issue #37; no ROS): the protocol file names the experiment, the
arms, seeds and budget, the endpoint and the statistics; this module turns it into campaign plans
and reads the campaigns' exports back against it, printing every deviation.

    python3 -m asg_analysis protocol plan experiments/protocol-round4.yaml pilot > results/round4/pilot.txt
    python3 -m asg_analysis protocol choose experiments/protocol-round4.yaml results/round4
    python3 -m asg_analysis protocol plan experiments/protocol-round4.yaml confirmatory \\
        --choice results/round4/pilot_choice.json > results/round4/plan.txt
    python3 -m asg_analysis protocol analyse experiments/protocol-round4.yaml results/round4

Plans are lines of scripts/repro/campaigns.sh (NAME SCENARIOS LAUNCH ARGS...); campaigns are named
PROTOCOL-ARM-sSEED (pilot: PROTOCOL-pilot-reward-REWARD-sSEED, PROTOCOL-pilot-band-BAND-sSEED).
`choose` applies the pilot's stated rule to the pilot's exports and writes the choice; `analyse`
counts, per arm and seed, the endpoint class per 1,000 scenarios and the secondary scores, and
compares the default with every other arm (asg_analysis.stats).
"""

import argparse
import json
import os
import sys
from typing import List, Optional

import yaml

from asg_agent.paths import REPO
from asg_agent.scoring import attribution as attr

PROG = "python3 -m asg_analysis protocol"

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


#: a campaign's keys and the train.launch argument each becomes, in the order a plan writes them:
#: the one translator from a protocol's arm to launch arguments (blocks.py's plans use it too)
LAUNCH_ARGS = (
    ("method", "method"),
    ("tabu_m", "tabu_m"),
    ("band_m", "route_band"),
    ("experiment", "experiment"),
    ("reward", "reward"),
    ("seed", "seed"),
    ("workers", "workers"),
    ("attribution", "attribution"),
    ("candidates", "candidates"),
)


def launch_value(v) -> str:
    """A protocol's value as train.launch reads it (YAML's false is the launch's `false`; 5.0 is `5`)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    return f"{v:g}" if isinstance(v, float) else str(v)


def launch_args(values: dict) -> List[str]:
    """The launch arguments of a campaign's values (keys of LAUNCH_ARGS; None and absent left out)."""
    unknown = sorted(set(values) - {k for k, _ in LAUNCH_ARGS})
    if unknown:
        raise ProtocolError(f"no launch argument for {', '.join(unknown)} (protocol.LAUNCH_ARGS)")
    return [f"{flag}:={launch_value(values[key])}" for key, flag in LAUNCH_ARGS if values.get(key) is not None]


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
    args = launch_args(
        {
            "method": method,
            "seed": seed,
            "experiment": experiment,
            "workers": p["workers"],
            "attribution": p["attribution"],
            "reward": reward,
            "band_m": None if band is None else float(band),
            "candidates": "all" if reward == "regret" else None,  # every scenario re-run on the references
        }
    )
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


def train_args(args: List[str]) -> List[str]:
    """A campaign's launch arguments as `bash scripts/train.sh` takes them for the product's default:
    the generator (method, experiment, reward, band), without the study's seed, workers and
    attribution."""
    return [a for a in args if a.split(":=", 1)[0] not in ("seed", "workers", "attribution")]


def run(argv=None) -> int:
    ap = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
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
    from asg_analysis.protocol_analysis import analyse, choose, status
    from asg_analysis.protocol_pages import class_labels, markers, status_markdown

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
    from asg_analysis.protocol_pages import class_labels, coverage_figure, markers, result_markdown

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
            from asg_analysis import budget as flaw_budget

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
