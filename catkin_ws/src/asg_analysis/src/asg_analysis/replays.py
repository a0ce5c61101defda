"""The replays of a campaign's findings (scripts/repro/replay_findings.sh writes one JSON a
campaign into FOLDER/replays/), as the table docs/experiments.md shows between its `replays`
markers (issue #54: every flaw finding of the default's first confirmatory seed replays exactly).
No ROS.

    python3 -m asg_analysis replays results/flaw_study [--doc docs/experiments.md]

Each study folder has its own block in the page, its markers naming the folder (markers()).
"""

import argparse
import glob
import json
import os
import sys
from typing import List


def markers(folder: str):
    """(begin, end) of FOLDER's replays block: round 5's study (results/flaw_study) keeps the
    markers it always had; another study's name its folder."""
    name = os.path.relpath(os.path.abspath(folder), REPO) if os.path.isabs(folder) else os.path.normpath(folder)
    if name == os.path.join("results", "flaw_study"):
        return (
            "<!-- replays: begin (generated from results/flaw_study/replays/; tests/test_flaw_study_doc.py) -->",
            "<!-- replays: end -->",
        )
    return (f"<!-- replays of {name}: begin (generated from {name}/replays/) -->", f"<!-- replays of {name}: end -->")


REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), *[".."] * 5))
BEGIN, END = markers(os.path.join("results", "flaw_study"))


def read(folder: str) -> List[dict]:
    """Every replay record of `folder`/replays/, by campaign name; the REPRODUCED count is the
    jobs' own verdicts, recounted."""
    out = []
    for path in sorted(glob.glob(os.path.join(folder, "replays", "*.json"))):
        with open(path, encoding="utf-8") as f:
            r = json.load(f)
        r["reproduced"] = sum(j["verdict"] == "REPRODUCED" for j in r["jobs"].values())
        r["findings"] = len(r["jobs"])
        out.append(r)
    return out


def markdown(records: List[dict]) -> str:
    rows = ["| campaign | flaw findings | REPRODUCED | CPU | numerics | commit |", "|---|---|---|---|---|---|"]
    rows += [
        f"| {r['campaign']} | {r['findings']} | {r['reproduced']} | {r['cpu']} | {r['numerics']} | {r['commit']} |"
        for r in records
    ]
    return "\n".join(rows)


def write_doc(doc: str, table: str, folder: str = os.path.join("results", "flaw_study"), check: bool = False) -> bool:
    """Rewrites the replays block of `doc` (check: write nothing, say whether it is current)."""
    from asg_analysis.docblocks import rewrite_between

    begin, end = markers(folder)
    rc = rewrite_between(doc, begin, end, f"{begin}\n{table}\n{end}", check, "replays")
    if rc == 2:
        raise ValueError(f"{doc}: no replays block ({begin} ... {end})")
    return rc == 0


def run(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("folder", help="the study's folder (its replays/ holds the records)")
    p.add_argument("--doc", default="", help="rewrite this page's replays block")
    p.add_argument("--check", action="store_true", help="with --doc: write nothing, exit 1 if the block is stale")
    a = p.parse_args(argv)
    table = markdown(read(a.folder))
    if a.doc:
        try:
            current = write_doc(a.doc, table, a.folder, a.check)
        except (OSError, ValueError) as e:
            print(f"replays: {e}", file=sys.stderr)
            return 2
        if not current:
            print(f"replays: {a.doc}'s replays block is stale: rerun without --check", file=sys.stderr)
            return 1
    print(table)
    return 0
