"""The design loop's hardening figures (issue #40; docs/design-loop.md): per arm, the per-pixel
figures on held-apart frames (evaluation-SET-ROUND.json of scripts/repro/harden.sh) and the pass
rate on each suite from the outcomes recorded in it.

    python3 -m asg_analysis hardening results/hardening [--json OUT] [--markdown]
    python3 -m asg_analysis hardening picture SUITE SCENARIO OUT.png LABEL=RESULTS.json ...

`picture`: one suite scenario as each stack drove it (the results are `suite run --json` files),
the paths on the scene top-down: a failure before and after hardening.
"""

import argparse
import glob
import json
import os
import re
import sys

import yaml

PROG = "python3 -m asg_analysis hardening"

SUITES = ("suite-exp1c", "suite-r4pilot")
SUITE_WORDS = {
    "suite-exp1c": "12 findings the findings arm trained on",
    "suite-r4pilot": "round 4 pilot's findings, no arm trained on",
}
SETS = ("test", "heldout-findings")
ARM_ORDER = ("flawed", "hardened-findings", "hardened-random", "full")


def arm_of(label: str):
    """The arm a suite label recorded by scripts/repro/harden.sh stands for (flawed-cl -> flawed,
    hardened-findings-1 as it is); None for the other labels a suite may carry (the committed
    suite's own records, on other backends)."""
    if label.endswith("-cl"):
        return label[:-3]
    return label if label.startswith("hardened-") else None


def _order(arm: str):
    base = re.sub(r"-\d+$", "", arm)
    n = re.search(r"-(\d+)$", arm)
    return (ARM_ORDER.index(base) if base in ARM_ORDER else len(ARM_ORDER), int(n.group(1)) if n else 0, arm)


def suite_passes(folder: str, leave_out=()) -> dict:
    """{arm: (passed, scenarios)} over the labels recorded in a suite (scenarios lacking a label
    are not counted for it), leaving out the scenarios of `leave_out`: (campaign, job) pairs."""
    from asg_agent.campaign.suite import verdict

    with open(os.path.join(folder, "suite.yaml"), encoding="utf-8") as f:
        suite = yaml.safe_load(f)
    out = {}
    gone = {(c, int(j)) for c, j in leave_out}
    for e in suite["scenarios"]:
        if (e.get("campaign"), int(e.get("job", -1))) in gone:
            continue
        for label, o in e.get("outcomes", {}).items():
            if "digest" not in o or arm_of(label) is None:  # exported from the campaign, or not ours
                continue
            failed, _ = verdict(o["termination"], o.get("proxy"), suite["bound"])
            k, n = out.get(arm_of(label), (0, 0))
            out[arm_of(label)] = (k + (not failed), n + 1)
    return out


def table(folder: str) -> dict:
    """{"arms": {arm: {set: {iou_non_traversable, shadow_false_obstacle_rate}, suite: {passed, n}}}}
    from the latest round's evaluation files and the suites in `folder`."""
    arms = {}
    for path in sorted(glob.glob(os.path.join(folder, "evaluation-*-*.json"))):
        m = re.match(r"evaluation-(.+)-(\d+)\.json$", os.path.basename(path))
        if not m or m.group(1) not in SETS:
            continue
        with open(path, encoding="utf-8") as f:
            for name, r in json.load(f)["results"].items():  # a later round's file overwrites the same arm's
                arms.setdefault(name, {})[m.group(1)] = {
                    "iou_non_traversable": r["iou"]["non_traversable"],
                    "shadow_false_obstacle_rate": r["shadow_false_obstacle_rate"],
                    "shadow_away_false_obstacle_rate": r["shadow_away_false_obstacle_rate"],
                }
    for s in SUITES:
        if os.path.isfile(os.path.join(folder, s, "suite.yaml")):
            for arm, (k, n) in suite_passes(os.path.join(folder, s)).items():
                arms.setdefault(arm, {})[s] = {"passed": k, "n": n}
    return {"arms": {a: arms[a] for a in sorted(arms, key=_order)}}


def markdown(t: dict) -> str:
    """The table of docs/design-loop.md (a suite no arm ran on gets no column)."""
    suites = [s for s in SUITES if any(s in r for r in t["arms"].values())]
    head = ["arm"]
    for s in SETS:
        head += [f"{s}: obstacle IoU", f"{s}: shadow false-obstacle"]
    head += [f"{s} passed ({SUITE_WORDS[s]})" for s in suites]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for arm, r in t["arms"].items():
        cells = [arm]
        for s in SETS:
            f = r.get(s)
            cells += [f"{f['iou_non_traversable']:.3f}", f"{f['shadow_false_obstacle_rate']:.3f}"] if f else ["", ""]
        for s in suites:
            f = r.get(s)
            cells.append(f"{f['passed']} / {f['n']}" if f else "")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


PATH_COLOURS = ("tab:red", "tab:blue", "tab:green", "tab:purple", "tab:orange")


def picture(suite_folder: str, scenario: str, runs: dict, out: str) -> dict:
    """Top-down picture of suite scenario `scenario` (its file, or the file's name without the
    folder) as each stack of `runs` ({label: results of `suite run --json`}) drove it; returns
    {label: (termination, proxy)}. The first label is drawn on top."""
    from asg_agent.campaign.suite import load_suite
    from asg_agent.scoring.proxy import optimal_path, placed_mask
    from asg_scenario.report import plot_run

    suite = load_suite(suite_folder)
    names = [e["file"] for e in suite["scenarios"]]
    hit = [k for k, f in enumerate(names) if f == scenario or os.path.basename(f) == os.path.basename(scenario)]
    if not hit:
        raise ValueError(f"{scenario!r}: not a scenario of {suite_folder} ({len(names)} there)")
    entry = suite["scenarios"][hit[0]]
    drawn, got = [], {}
    for k, (label, results) in enumerate(runs.items()):
        r = next((x for x in results if x.get("file") == entry["file"]), None)
        if r is None:
            raise ValueError(f"{label}: its results have no run of {entry['file']}")
        if not r.get("trajectory_xy"):
            raise ValueError(f"{label}: its results carry no path (made before suite run kept paths)")
        p = "n/a" if r.get("proxy") is None else f"{r['proxy']:.2f}"
        text = f"{label}: {r['reason'] if r['fails'] else 'passes'}, proxy {p}"
        same = [lab for lab, (xy, _) in got.items() if xy == r["trajectory_xy"]]
        if same:  # drawn under it: say so, or the legend shows a path the picture hides
            text += f" (the path of {same[0]})"
        drawn.append((text, r["trajectory_xy"], PATH_COLOURS[k % 5]))
        got[label] = (r["trajectory_xy"], (r["termination"], r.get("proxy")))
    req = entry["request"]
    opt = optimal_path(req, placed_mask(req, []))
    title = f"{entry['file']}\n{entry.get('campaign', '')} job {entry.get('job', '?')}\n{entry.get('mode', '')}"
    (label0, xy0, _), rest = drawn[0], drawn[1:]
    plot_run(out, req, xy0, title=title, optimal=opt.points, label=label0, others=rest)
    return {label: outcome for label, (_, outcome) in got.items()}


def run(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv[:1] == ["picture"]:
        q = argparse.ArgumentParser(prog=PROG + " picture", description=picture.__doc__.split("\n")[0])
        q.add_argument("suite")
        q.add_argument("scenario")
        q.add_argument("out")
        q.add_argument("runs", nargs="+", help="LABEL=RESULTS.json (suite run --json)")
        b = q.parse_args(argv[1:])
        try:
            runs = {}
            for spec in b.runs:
                label, _, path = spec.partition("=")
                if not path:
                    raise ValueError(f"{spec!r}: expected LABEL=RESULTS.json")
                with open(path, encoding="utf-8") as f:
                    runs[label] = json.load(f)
            for label, (term, proxy) in picture(b.suite, b.scenario, runs, b.out).items():
                print(f"{label}: {term}, proxy {proxy}")
        except (OSError, ValueError, KeyError) as e:
            print(f"error: {e}", file=sys.stderr)
            return 2
        print(f"wrote {b.out}")
        return 0
    p = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    p.add_argument("folder")
    p.add_argument("--json", default="")
    p.add_argument("--markdown", action="store_true")
    a = p.parse_args(argv)
    if not os.path.isdir(a.folder):
        print(f"error: {a.folder}: no such folder", file=sys.stderr)
        return 2
    t = table(a.folder)
    if a.json:
        with open(a.json, "w", encoding="utf-8") as f:
            json.dump(t, f, indent=1)
    print(markdown(t) if a.markdown else json.dumps(t, indent=1))
    return 0
