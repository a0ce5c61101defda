"""atlas: a scene's failure atlas, built from campaign exports, and what a campaign covers (no ROS).

    rosrun asg_agent atlas build --kind flaw --out results/atlas/exp1-flaw.json EXPORT.jsonl.gz [...]
    rosrun asg_agent atlas add results/atlas/exp1-flaw.json EXPORT.jsonl.gz [...]
    rosrun asg_agent atlas show results/atlas/exp1-flaw.json
    rosrun asg_agent atlas recall results/atlas/exp1-flaw.json EXPORT.jsonl.gz [...] [--budget 300]

`build` pools the findings of `--kind` (flaw: three-stack attribution's flaw class; regression: a
release pair's; failure: the stack's own failed runs) of every export of one identity (the scene,
the stack under test and its references: the first usable export's), skips every other export
saying why, and writes the atlas (scoring/atlas.py: places at 5 m and 2 m, growth curve, Chao1
completeness); over a file of the same identity it writes the next version, unless its places are
the same. `add` writes the next version with the exports' findings pooled in (exports of
runs the atlas holds count once). `recall` gives, per export, the places it covers within its
first BUDGET scenarios, per class, the scenarios it took to cover half, and the places it found
beyond the atlas (new). Exit status 2 on a file that cannot be read or an export of another
identity, naming it.
"""

import argparse
import glob
import json
import sys

from asg_agent.records import atlas as ra
from asg_agent.records.export import read_export
from asg_agent.scoring import atlas as sa
from asg_agent.scoring.places import place_of_row


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="atlas", description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    b = sub.add_parser("build", help="an atlas from exports (one identity; the others skipped, each with why)")
    b.add_argument("--kind", choices=sa.KINDS, required=True, help="the findings it pools")
    b.add_argument("--out", required=True, help="the atlas file to write (JSON)")
    b.add_argument(
        "--like", default="", help="the export whose identity the atlas takes (default: the first usable one)"
    )
    b.add_argument("exports", nargs="+", help="campaign exports (globs are expanded)")
    a = sub.add_parser("add", help="the atlas's next version, with the exports' findings pooled in")
    a.add_argument("atlas")
    a.add_argument("exports", nargs="+")
    s = sub.add_parser("show", help="an atlas's identity, places per class, growth and completeness")
    s.add_argument("atlas")
    r = sub.add_parser("recall", help="the atlas's places each export covers")
    r.add_argument("atlas")
    r.add_argument("exports", nargs="+")
    r.add_argument("--budget", type=int, default=300, help="scenarios of each export counted (default 300)")
    r.add_argument("--radius", type=float, default=sa.RADIUS_M, help=f"[m] the grouping (default {sa.RADIUS_M:g})")
    r.add_argument("--json", action="store_true", help="one JSON object per export")
    return p


def _paths(patterns):
    out = []
    for p in patterns:
        hits = sorted(glob.glob(p, recursive=True))
        out.extend(hits or [p])
    return out


def summary_lines(d: dict) -> list:
    """What `show` prints of an atlas file."""
    i = d["identity"]
    lines = [
        f"atlas v{d['version']}: {i['kind']} findings of stack {i['stack']} ({i['perception']}"
        + (f", model {i['model']}, {i['unet_backend']}" if i.get("model") else "")
        + f") on {i['scene']}; {len(d['sources'])} campaigns, {d['scenarios']} scenarios, {len(d['findings'])} findings"
    ]
    for g in d["groupings"]:
        c, c2 = g["chao1"], g["chao2"]
        per = ", ".join(f"{k} {v}" for k, v in sorted(g["by_class"].items()))
        half = g["growth"][len(g["growth"]) // 2]
        lines.append(
            f"  at {g['radius_m']:g} m: {c['observed']} places ({per}); seen by one finding {c['f1']}, by two "
            f"{c['f2']}: Chao1 {c['chao1']:.1f}, completeness {c['completeness']:.2f}; found by one campaign "
            f"{c2['q1']}, by two {c2['q2']}: Chao2 {c2['chao2']:.1f}, completeness {c2['completeness']:.2f}; "
            f"{half[1]} of them within the first {half[0]} of the pooled scenarios (shuffled)"
        )
    return lines


def recall_of(atlas: sa.Atlas, rows, budget: int) -> dict:
    """An export's coverage of `atlas` within its first `budget` scenarios (job order)."""
    cov = sa.Coverage(atlas)
    half_at = None
    rows = sorted(rows, key=lambda r: r["job"])[:budget]
    for n, r in enumerate(rows, 1):
        if sa.is_finding(r, atlas.identity["kind"]):
            cov.add(place_of_row(r))
            if half_at is None and 2 * len(cov.covered) >= len(atlas):
                half_at = n
    return dict(cov.counts(), recall=cov.recall(), scenarios=len(rows), half_at=half_at)


def main(argv=None) -> int:
    args = parser().parse_args(argv)
    try:
        if args.cmd == "build":
            d, skipped = ra.build_from(_paths(args.exports), args.kind, args.like or None)
            d["version"] = ra.next_version(args.out, d)
            ra.write(d, args.out)
        elif args.cmd == "add":
            d, skipped = ra.add(ra.read(args.atlas), _paths(args.exports))
            ra.write(d, args.atlas)
        elif args.cmd == "show":
            print("\n".join(summary_lines(ra.read(args.atlas))))
            return 0
        else:
            return _recall(args)
    except ValueError as e:
        print(f"atlas: {e}", file=sys.stderr)
        return 2
    for path, why in skipped:
        print(f"skipped {path}: {why}")
    print("\n".join(summary_lines(d)))
    print(f"wrote {args.out if args.cmd == 'build' else args.atlas}")
    return 0


def _recall(args) -> int:
    atlas = sa.load(args.atlas, args.radius)
    for path in _paths(args.exports):
        campaign, rows = read_export(path)
        why = ra.usable(campaign, atlas.identity["kind"])
        diff = sa.same_identity(atlas.identity, ra.identity(campaign, atlas.identity["kind"])) if why is None else []
        if why or diff:
            print(
                f"atlas: {path}: " + (why or "another identity than the atlas's: " + ", ".join(diff)), file=sys.stderr
            )
            return 2
        r = recall_of(atlas, rows, args.budget)
        if args.json:
            print(json.dumps(dict(r, export=path, campaign=campaign["name"]), sort_keys=True))
        else:
            half = f"half covered after {r['half_at']} scenarios" if r["half_at"] else "half never covered"
            print(
                f"{campaign['name']}: recall {r['recall']:.2f} in {r['scenarios']} scenarios: {sa.coverage_text(r)}; {half}"
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
