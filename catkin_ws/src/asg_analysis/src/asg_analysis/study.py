"""One study runner driven by the protocol file (issue #80 item 1; no ROS).

A protocol's `report:` list names every generated block of its study record, what fills it and
from which exports, so that a new study is a protocol file and the record regenerates with one
command:

    python3 -m asg_analysis study experiments/protocol-NAME.yaml            # rewrite every block
    python3 -m asg_analysis study experiments/protocol-NAME.yaml --check    # exit 1 if one is stale

Each entry of `report:`:

    - page: docs/studies/DATE-NAME.md         # the record (relative to the repository)
      block: NAME                              # its <!-- NAME: begin --> ... <!-- NAME: end -->
      table: campaigns                         # one row a campaign (endpoints.markdown)
      exports: results/STUDY/GLOB.jsonl.gz     # the campaigns' compact exports (a glob or a list)
      budget: 150                              # count the first N jobs (optional)
      target: flaw                             # flaw, regression or failure (default flaw)

    - page: ...
      block: ...
      table: arms                              # arms compared (endpoints.comparison_markdown)
      arms: {default: GLOB, route-random: GLOB}   # the default first
      budget: 300

    - page: ...
      block: ...
      table: rules                             # learnt rules and the first one's check (rules.markdown)
      rules: results/STUDY/rules.json          # what `asg_analysis.rules learn --out` wrote
      exports: results/STUDY/RULE-SAMPLER-GLOB.jsonl.gz   # the check's fresh samples (optional)
      base: results/STUDY/RANDOM-GLOB.jsonl.gz             # the same sampler without the rule
      target: flaw

    - page: ...
      block: ...
      table: digests                           # seeded results digests, one line each
      digests: {"before (COMMIT)": results/bench/TAG-before-1.digest, ...}

    - table: command                           # a generator of its own that writes its block(s)
      command: protocol                        # python3 -m asg_analysis COMMAND ARGS, run in-process
      args: [status, experiments/protocol-NAME.yaml, results/STUDY, --doc, docs/studies/DATE-NAME.md]
      check: [--check]                          # added with --check (the default)
      blocks: [NAME, ...]                      # the blocks it writes (what the record tests match)

The statistics are the library's (asg_analysis.endpoints, asg_analysis.stats); an entry names
only what to read and where to write. An entry whose exports match nothing is named and its block
left as it is (a study under way).
"""

import argparse
import glob
import os
import sys
from typing import Dict, List

import yaml

from asg_agent.paths import REPO
from asg_analysis.docblocks import block_text

PROG = "python3 -m asg_analysis study"

TABLES = ("campaigns", "arms", "rules", "digests", "coverage")
KINDS = TABLES + ("command",)


def _paths(pattern) -> List[str]:
    """The files of one glob, or of a list of them, sorted."""
    patterns = [pattern] if isinstance(pattern, str) else list(pattern)
    return sorted({p for pat in patterns for p in glob.glob(os.path.join(REPO, pat))})


def render(entry: Dict) -> str:
    """The block's text of one `report:` entry (ValueError naming what is wrong)."""
    from asg_agent.records.export import read_export
    from asg_analysis import endpoints

    kind = entry.get("table")
    if kind not in TABLES:
        raise ValueError(f"report entry {entry.get('block')!r}: table {kind!r} must be one of {', '.join(KINDS)}")
    budget = entry.get("budget")
    target = entry.get("target", "flaw")
    target = None if target == "failure" else target
    if kind == "rules":
        return _rules(entry, target)
    if kind == "digests":
        return _digests(entry["digests"])
    if kind == "coverage":  # protocol v5's blocks (asg_analysis.coverage.record_blocks)
        from asg_analysis.coverage import record_blocks

        return "\n".join(record_blocks()[entry["block"]].splitlines()[1:-1]) + "\n"
    if kind == "campaigns":
        paths = _paths(entry["exports"])
        if not paths:
            raise FileNotFoundError(f"no export matches {entry['exports']}")
        return endpoints.markdown(
            [endpoints.campaign(*read_export(p), budget=budget, target=target) for p in paths], target
        )
    arms = {name: _paths(pattern) for name, pattern in entry["arms"].items()}
    empty = [name for name, ps in arms.items() if not ps]
    if empty:
        raise FileNotFoundError(f"no export of arm(s) {', '.join(empty)}")
    res = endpoints.compare(arms, next(iter(arms)), budget, target)
    return endpoints.comparison_markdown(res)


def _rules(entry: Dict, target) -> str:
    """The `rules` table: the learnt rules, the first checked on fresh samples once they are in."""
    import json

    from asg_analysis import rules
    from asg_analysis.exports import read_rows

    with open(os.path.join(REPO, entry["rules"]), encoding="utf-8") as f:
        learnt = json.load(f)
    checked = None
    if entry.get("exports"):
        fresh, base = _paths(entry["exports"]), _paths(entry["base"])
        if fresh and base:
            checked = rules.check(read_rows(fresh, "", "")[0], read_rows(base, "", "")[0], target)
    return rules.markdown(learnt, checked)


def _digests(digests: Dict[str, str]) -> str:
    """One line a digest file (`N SHA256`, what bench_before_after.sh writes): its label, path, the
    number of results and the digest's first eight hex digits."""
    lines = []
    for label, path in digests.items():
        with open(os.path.join(REPO, path), encoding="utf-8") as f:
            n, sha = f.read().split()
        lines.append(f"- {label}: `{path}`, {n} results, {sha[:8]}")
    return "\n".join(lines) + "\n"


def _command(e: Dict, check: bool, out) -> int:
    """Runs a `command` entry in this process (a command of asg_analysis.commands that writes its
    own blocks); 1 when --check finds it stale."""
    import contextlib
    import io

    from asg_analysis import commands

    name = e.get("command")
    if name not in commands.COMMANDS:
        raise ValueError(f"report entry {e.get('blocks')}: command {name!r} is not one of python3 -m asg_analysis's")
    args = [str(x) for x in e.get("args", [])]
    if check:
        args += [str(x) for x in e.get("check", ["--check"])]
    said = io.StringIO()
    with contextlib.redirect_stdout(said), contextlib.redirect_stderr(said):
        rc = commands.call(name, args)
    what = f"{name} {' '.join(args[:3])}"
    if rc == 0:
        print(f"{what}: {'in step' if check else 'written'}", file=out)
        return 0
    if check:
        print(f"{what}: stale (exit {rc}) {said.getvalue().strip()[-300:]}", file=out)
        return 1
    raise ValueError(f"{what} failed (exit {rc}): {said.getvalue().strip()[-500:]}")


def regenerate(protocol_path: str, check: bool = False, out=None) -> int:
    from asg_analysis.endpoints import write_block  # docblocks

    out = out or sys.stdout

    with open(protocol_path, encoding="utf-8") as f:
        protocol = yaml.safe_load(f)
    entries = (protocol or {}).get("report") or []
    if not entries:
        raise ValueError(f"{protocol_path}: no `report:` list (the blocks of its study record)")
    stale = 0
    for e in entries:
        if e.get("table") == "command":
            stale += _command(e, check, out)
            continue
        page = os.path.join(REPO, e["page"])
        try:
            text = render(e)
        except FileNotFoundError as err:
            print(f"{e['block']}: skipped, {err}", file=out)
            continue
        if check:
            if block_text(page, e["block"]).strip() != text.strip():
                print(f"{e['page']}: block {e['block']!r} is stale", file=out)
                stale += 1
        else:
            write_block(page, e["block"], text)
            print(f"{e['page']}: block {e['block']!r} written", file=out)
    return 1 if stale else 0


def run(argv=None) -> int:
    p = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    p.add_argument("protocol", help="a protocol file with a `report:` list")
    p.add_argument("--check", action="store_true", help="exit 1 if a block is stale; write nothing")
    a = p.parse_args(argv)
    try:
        return regenerate(a.protocol, a.check)
    except (OSError, ValueError, KeyError, yaml.YAMLError) as e:
        print(f"study: {e}", file=sys.stderr)
        return 2
