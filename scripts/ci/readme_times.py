#!/usr/bin/python3
"""The README's times block (issue #79): each command's newest record in results/readme_times/
(written by scripts/repro/readme_times.sh, never by hand), with the CPU it ran on.
    python3 scripts/ci/readme_times.py --doc README.md     # rewrites the block
    python3 scripts/ci/readme_times.py                     # prints it"""

import glob
import json
import os
import sys

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", ".."))
BEGIN, END = "<!-- times: begin -->\n", "<!-- times: end -->"
ORDER = ("demo", "train", "test")


def records(folder=os.path.join(REPO, "results", "readme_times")):
    """{command name: its newest record that exited 0}."""
    out = {}
    for path in sorted(glob.glob(os.path.join(folder, "*.json"))):
        rec = json.load(open(path, encoding="utf-8"))
        name = rec["command"].split("/")[-1][: -len(".sh")]
        if rec["exit"] == 0 and (name not in out or rec["date"] >= out[name]["date"]):
            out[name] = rec
    return out


def minutes(s: float) -> str:
    m, sec = divmod(int(round(s)), 60)
    return f"{m} min {sec:02d} s" if m else f"{sec} s"


def block(recs) -> str:
    lines = []
    for name in ORDER:
        r = recs.get(name)
        if r:
            built = "the workspace already built" if r["built_before"] else "installing and building first"
            lines.append(
                f"`{r['command']}`: {minutes(r['wall_s'])} on a {r['cores']}-core {r['cpu']} ({r['cpu_kind']}), "
                f"{built} ({r['date']}, {r['commit']})."
            )
    body = "Measured times: " + " ".join(lines) if lines else "No times measured yet."
    return BEGIN + body + "\n" + END


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    text = block(records())
    if argv[:1] == ["--doc"]:
        path = argv[1]
        doc = open(path, encoding="utf-8").read()
        if BEGIN not in doc or END not in doc:
            print(f"readme_times: {path} has no times block", file=sys.stderr)
            return 2
        head, rest = doc.split(BEGIN, 1)
        doc = head + text + rest.split(END, 1)[1]
        open(path, "w", encoding="utf-8").write(doc)
    else:
        print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
