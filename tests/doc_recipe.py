"""docs/your-stack.md's install-space recipe, steps 4-8, as the page writes them (issue #68): the
bash blocks of those steps pulled from the page and turned into a script that stops at the first
failing command and names it. Only these words change, each for a reason a test can check:

- `--layouts 300` and `scenarios:=150`: the baseline's and the campaign's sizes (a test's budget);
- `JOB`: the page's placeholder for a job number (the campaign's first, 0);
- `python3`: /usr/bin/python3 (Debian's ROS lives in its site-packages);
- before step 7, which says "Stop step 4's worker and rviz (the master stays)", the step-4
  commands started in the background are stopped, but for the master (the page says it in words;
  a script says it with `kill`); the master is stopped at the end.
Nothing else is added: no master of the script's own (issue #79: the page's step 4 starts it), and
no exit status is excused.

    python3 tests/doc_recipe.py [--layouts 3] [--scenarios 5] > steps.sh
"""

import argparse
import os
import re
import shlex
import sys

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
DOC = os.path.join(REPO, "docs", "your-stack.md")
SECTION = "## From an install space: your own stack, step by step"
STEPS = (4, 5, 6, 7, 8)


#: stops what the steps started in the background (under `set -e`: nothing here may fail)
STOP = 'if [ ${#BG[@]} -gt 0 ]; then kill -INT "${BG[@]}" 2>/dev/null || true; wait "${BG[@]}" 2>/dev/null || true; BG=(); fi'


def step_blocks(text: str) -> dict:
    """{step number: [command lines]} of the section's numbered steps' ```bash blocks, each command
    with its continuation lines joined."""
    body = text[text.index(SECTION) :]
    body = body[: body.index("\n## ", len(SECTION))]
    out = {}
    for m in re.finditer(r"^(\d+)\. \*\*.*?(?=^\d+\. \*\*|\Z)", body, re.S | re.M):
        blocks = re.findall(r"```bash\n(.*?)```", m.group(0), re.S)
        lines = []
        for b in blocks:
            joined = re.sub(r"\\\n\s*", "", b)
            lines += [ln.strip() for ln in joined.splitlines() if ln.strip()]
        out[int(m.group(1))] = lines
    return out


def substitute(line: str, layouts: int, scenarios: int) -> str:
    line = line.replace("--layouts 300", f"--layouts {layouts}").replace("scenarios:=150", f"scenarios:={scenarios}")
    return re.sub(r"\bJOB\b", "0", line)


def script(text: str, layouts: int = 3, scenarios: int = 5) -> str:
    steps = step_blocks(text)
    missing = [s for s in STEPS if not steps.get(s)]
    if missing:
        raise ValueError(f"{DOC}: no bash block under step(s) {missing}")
    out = [
        'python3() { /usr/bin/python3 "$@"; }',
        "BG=()",
        'fail() { echo "RECIPE FAILED at step $1: $2" >&2; exit 1; }',
    ]
    for s in STEPS:
        out.append(f'echo "== step {s}"')
        if s == 7:
            out.append(STOP)
        for line in steps[s]:
            cmd = substitute(line, layouts, scenarios)
            if cmd.endswith("&") and cmd.split()[0] == "roscore":
                out.append(f"{cmd} CORE=$!")  # the master stays until the end
            elif cmd.endswith("&"):
                out.append(f"{cmd} BG+=($!)")
            elif " replay " in f" {cmd} ":
                out.append(f'OUT=$({cmd} 2>&1) || {{ echo "$OUT" | tail -20; fail {s} {shlex.quote(cmd)}; }}')
                out.append('echo "$OUT" | tail -4')
            else:
                out.append(f"{cmd} || fail {s} {shlex.quote(cmd)}")
    out.append(STOP)
    out.append(
        'if [ -n "${CORE:-}" ]; then kill -INT "$CORE" 2>/dev/null || true; wait "$CORE" 2>/dev/null || true; fi'
    )
    out.append('echo "== steps 4-8 ran as the page writes them"')
    return "\n".join(out) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="doc_recipe", description=__doc__.split("\n\n")[0])
    ap.add_argument("--layouts", type=int, default=3)
    ap.add_argument("--scenarios", type=int, default=5)
    a = ap.parse_args(argv)
    with open(DOC, encoding="utf-8") as f:
        sys.stdout.write(script(f.read(), a.layouts, a.scenarios))
    return 0


if __name__ == "__main__":
    sys.exit(main())
