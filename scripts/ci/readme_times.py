#!/usr/bin/python3
"""The README's times block: each command's newest record in results/readme_times/ (written by
scripts/repro/readme_times.sh, never by hand), with the CPU it ran on; a newest run that failed
is shown as failed, beside the newest that passed; a record whose command's files changed since
its commit is stale (tests/test_readme_times.py fails until it is measured again).
    python3 scripts/ci/readme_times.py --doc README.md     # rewrites the block
    python3 scripts/ci/readme_times.py --doc docs/benchmarks.md   # its AVX2-only train.sh runs
    python3 scripts/ci/readme_times.py --doc PAGE --check  # exit 1 if a block is stale
    python3 scripts/ci/readme_times.py                     # prints it"""

import glob
import json
import os
import sys

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", ".."))
BEGIN, END = "<!-- times: begin -->\n", "<!-- times: end -->"
ORDER = ("demo", "train", "test")


def all_records(folder=os.path.join(REPO, "results", "readme_times")):
    """{command name: its records, oldest first}."""
    out = {}
    for path in sorted(glob.glob(os.path.join(folder, "*.json"))):
        rec = json.load(open(path, encoding="utf-8"))
        out.setdefault(rec["command"].split("/")[-1][: -len(".sh")], []).append(rec)
    return {k: sorted(v, key=lambda r: r["date"]) for k, v in out.items()}


def records(folder=os.path.join(REPO, "results", "readme_times")):
    """{command name: its newest record, passing or not}."""
    return {k: v[-1] for k, v in all_records(folder).items()}


def passing(folder=os.path.join(REPO, "results", "readme_times")):
    """{command name: its newest record that exited 0}."""
    out = {}
    for k, v in all_records(folder).items():
        ok = [r for r in v if r["exit"] == 0]
        if ok:
            out[k] = ok[-1]
    return out


#: the files whose change makes a command's time stale (the command and what it sources)
FILES = {
    "demo": ("scripts/demo.sh", "scripts/common.sh"),
    "train": ("scripts/train.sh", "scripts/common.sh", "launch/train.launch"),
    "test": ("scripts/test.sh", "scripts/common.sh"),
}


def stale(rec) -> list:
    """The files of a record's command changed since its commit (git; [] when unchanged)."""
    import subprocess

    name = rec["command"].split("/")[-1][: -len(".sh")]
    r = subprocess.run(
        ["git", "-C", REPO, "diff", "--name-only", rec["commit"], "HEAD", "--", *FILES[name]],
        capture_output=True,
        text=True,
    )
    if r.returncode != 0:
        return [f"(commit {rec['commit']} unknown here)"]
    return r.stdout.split()


def minutes(s: float) -> str:
    m, sec = divmod(int(round(s)), 60)
    return f"{m} min {sec:02d} s" if m else f"{sec} s"


def _one(r) -> str:
    built = (
        "the workspace already built"
        if r["built_before"]
        else "in a fresh clone, installing what is missing and building first"
    )
    return f"{minutes(r['wall_s'])} on a {r['cores']}-core {r['cpu']} ({r['cpu_kind']}), {built} ({r['date']}, {r['commit']})"


def block(recs, ok=None) -> str:
    """The README's block: each command's newest record; a newest run that failed is said, with
    the newest passing run beside it (`ok`: passing())."""
    ok = passing() if ok is None else ok
    lines = []
    for name in ORDER:
        r = recs.get(name)
        if not r:
            continue
        if r["exit"] == 0:
            lines.append(f"`{r['command']}`: {_one(r)}.")
        else:
            prev = ok.get(name)
            lines.append(
                f"`{r['command']}`: its newest run exited {r['exit']} after {_one(r)}"
                + (f"; the newest that passed: {_one(prev)}." if prev else "; none has passed yet.")
            )
    body = "Measured times: " + " ".join(lines) if lines else "No times measured yet."
    return BEGIN + body + "\n" + END


AVX2_BEGIN, AVX2_END = "<!-- avx2 train: begin -->\n", "<!-- avx2 train: end -->"


def avx2_train_block(recs=None) -> str:
    """docs/benchmarks.md's measured train.sh runs on an AVX2-only CPU (every record that passed)."""
    runs = [r for r in (recs if recs is not None else all_records()).get("train", []) if r["cpu_kind"] == "AVX2-only"]
    runs = [r for r in runs if r["exit"] == 0]
    if not runs:
        return AVX2_BEGIN + "No run on an AVX2-only CPU is recorded yet.\n" + AVX2_END
    lines = [f"- `{r['command']}`: {_one(r)}." for r in runs]
    under = all(r["wall_s"] < 15 * 60 for r in runs)
    lines.append(f"- {'every run under' if under else 'not every run under'} the 15 minutes.")
    return AVX2_BEGIN + "\n".join(lines) + "\n" + AVX2_END


def _rewrite(doc: str, begin: str, end: str, text: str) -> str:
    head, rest = doc.split(begin, 1)
    return head + text + rest.split(end, 1)[1]


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    text = block(records(), passing())
    check = "--check" in argv
    argv = [a for a in argv if a != "--check"]
    if argv[:1] == ["--doc"]:
        path = argv[1]
        doc = old = open(path, encoding="utf-8").read()
        found = False
        if BEGIN in doc and END in doc:
            doc, found = _rewrite(doc, BEGIN, END, text), True
        if AVX2_BEGIN in doc and AVX2_END in doc:
            doc, found = _rewrite(doc, AVX2_BEGIN, AVX2_END, avx2_train_block()), True
        if not found:
            print(f"readme_times: {path} has no times block", file=sys.stderr)
            return 2
        if check:  # --check: exit 1 if a block is stale, write nothing
            return 0 if doc == old else 1
        open(path, "w", encoding="utf-8").write(doc)
    else:
        print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
