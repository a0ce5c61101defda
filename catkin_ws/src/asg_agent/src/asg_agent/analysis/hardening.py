"""The design loop's hardening figures (issue #40; docs/design-loop.md): per arm, the per-pixel
figures on held-apart frames (evaluation-SET-ROUND.json of scripts/repro/harden.sh) and the pass
rate on each suite from the outcomes recorded in it.

    python3 -m asg_agent.analysis.hardening results/hardening [--json OUT] [--markdown]
"""

import argparse
import glob
import json
import os
import re
import sys

import yaml

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


def suite_passes(folder: str) -> dict:
    """{arm: (passed, scenarios)} over the labels recorded in a suite (scenarios lacking a label
    are not counted for it)."""
    from asg_agent.campaign.suite import verdict

    with open(os.path.join(folder, "suite.yaml"), encoding="utf-8") as f:
        suite = yaml.safe_load(f)
    out = {}
    for e in suite["scenarios"]:
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


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="analysis.hardening", description=__doc__.split("\n\n")[0])
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


if __name__ == "__main__":
    sys.exit(main())
