"""The replays of a campaign's findings (scripts/repro/replay_findings.sh writes one JSON a
campaign into FOLDER/replays/), as the table docs/experiments.md shows between its `replays`
markers (issue #54: every flaw finding of the default's first confirmatory seed replays exactly).
No ROS.

    python3 -m asg_analysis.replays results/flaw_study [--doc docs/experiments.md]
"""

import argparse
import glob
import json
import os
import re
import sys
from typing import List

BEGIN = "<!-- replays: begin (generated from results/flaw_study/replays/; tests/test_flaw_study_doc.py) -->"
END = "<!-- replays: end -->"


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


def write_doc(doc: str, table: str) -> None:
    with open(doc, encoding="utf-8") as f:
        text = f.read()
    pattern = re.escape(BEGIN) + r"\n.*?\n" + re.escape(END)
    if not re.search(pattern, text, re.S):
        raise ValueError(f"{doc}: no replays block ({BEGIN} ... {END})")
    with open(doc, "w", encoding="utf-8") as f:
        f.write(re.sub(pattern, lambda _: f"{BEGIN}\n{table}\n{END}", text, flags=re.S))


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("folder", help="the study's folder (its replays/ holds the records)")
    p.add_argument("--doc", default="", help="rewrite this page's replays block")
    a = p.parse_args(argv)
    table = markdown(read(a.folder))
    if a.doc:
        try:
            write_doc(a.doc, table)
        except (OSError, ValueError) as e:
            print(f"replays: {e}", file=sys.stderr)
            return 2
    print(table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
