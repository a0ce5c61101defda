"""Every generated block of README.md and docs/, rewritten or checked with one command (no ROS).

    python3 -m asg_analysis docs             # rewrite every block, in the order below
    python3 -m asg_analysis docs --check     # exit 1 naming each stale block; write nothing
    python3 -m asg_analysis docs --list      # each block and what writes it

A block is the text between a page's `<!-- NAME: begin ... -->` and `<!-- NAME: end -->` (older
pages write `NAME:begin`). Each one has exactly one writer here, and the writers run in order:

1. the studies: each file of experiments/ with a `report:` list (`python3 -m asg_analysis study`);
2. the library's commands that write a page of their own (coverage, defaults, held-apart,
   reliability);
3. the tables read from the code: each node's parameter table, the package picture of
   docs/architecture.md, the index of docs/studies/, the mechanism table, the pilot's choice;
4. the scripts of scripts/ci (the README's measured times, the repeated rostests);
5. last, docs/testing.md's summary of every page's figures (scripts/ci/doc_figures.py), which
   reads what the others wrote.

A block written by hand and checked by a test (CHECKED) is named with its test and left alone.
asg_analysis/test/test_docs.py holds this table to the pages: every block of a page has one writer
or is CHECKED, and every block named here is on its page.
"""

import argparse
import contextlib
import glob
import importlib.util
import io
import json
import os
import re
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from typing import Callable, Dict, List, Optional, Tuple

import yaml

from asg_agent.paths import REPO

PROG = "python3 -m asg_analysis docs"
PAGES = ("README.md", "docs")
# <!-- NAME: begin ... -->, <!-- NAME:begin ... --> (NAME may hold a colon: params:scene_worker)
BEGIN = re.compile(r"<!-- ([^>]*?):\s?begin\b[^>]*-->")


@dataclass
class Writer:
    """One writer: what --list calls it, the blocks it writes ((page, name), pages relative to the
    repository) and `write(check) -> exit` (0 in step or written, 1 stale, 2 it could not run)."""

    name: str
    blocks: List[Tuple[str, str]]
    write: Callable[[bool], int]


# Blocks written by hand and checked by a test: (page, name) -> the test.
CHECKED = {
    ("docs/testing.md", "suite lanes"): "tests/test_suite_times.py (the prose's figures are the records')",
}


def page_blocks(root: str = REPO) -> List[Tuple[str, str]]:
    """Every (page, block name) of README.md and docs/**.md, in page order."""
    out = []
    files = [os.path.join(root, "README.md")] + sorted(
        glob.glob(os.path.join(root, "docs", "**", "*.md"), recursive=True)
    )
    for path in files:
        if os.path.isfile(path):
            text = open(path, encoding="utf-8").read()
            out += [(os.path.relpath(path, root), m.group(1).strip()) for m in BEGIN.finditer(text)]
    return out


def _markers(text: str, name: str) -> Tuple[str, str]:
    """The begin marker of block NAME as the page writes it, and its end marker."""
    for m in BEGIN.finditer(text):
        if m.group(1).strip() == name:
            sep = m.group(0)[len("<!-- ") + len(name) : m.group(0).index("begin")]
            return m.group(0), f"<!-- {name}{sep}end -->"
    raise ValueError(f"no block {name!r}")


def rewrite_body(page: str, name: str, body: str, check: bool, inline: bool = False) -> int:
    """Writes `body` as block NAME of `page` (relative), its markers as the page has them; a block
    written in a line of prose (`inline`) has no line breaks at its ends."""
    from asg_analysis.docblocks import rewrite_between

    path = os.path.join(REPO, page)
    try:
        begin, end = _markers(open(path, encoding="utf-8").read(), name)
    except ValueError as e:
        print(f"{PROG}: {page}: {e}", file=sys.stderr)
        return 2
    block = f"{begin}{body}{end}" if inline else f"{begin}\n{body.rstrip(chr(10))}\n{end}"
    return rewrite_between(path, begin, end, block, check, PROG)


def _quiet(fn: Callable[[], int]) -> Tuple[int, str]:
    said = io.StringIO()
    with contextlib.redirect_stdout(said), contextlib.redirect_stderr(said):
        try:
            rc = int(fn() or 0)
        except SystemExit as e:
            rc = e.code if isinstance(e.code, int) else 2
    return rc, said.getvalue()


# -- 1. studies -------------------------------------------------------------------------------


def study_writers() -> List[Writer]:
    """One writer a file of experiments/ with a `report:` list."""
    from asg_analysis import study

    out = []
    for path in sorted(glob.glob(os.path.join(REPO, "experiments", "*.yaml"))):
        with open(path, encoding="utf-8") as f:
            entries = (yaml.safe_load(f) or {}).get("report") or []
        if not entries:
            continue
        blocks = []
        for e in entries:
            if e.get("table") == "command":
                args = [str(a) for a in e.get("args", [])]
                doc = [args[i + 1] for i, a in enumerate(args[:-1]) if a in ("--doc", "--docs")]
                page = e.get("page") or (doc[0] if doc else None)
                if not page:
                    raise ValueError(f"{os.path.relpath(path, REPO)}: entry {e.get('blocks')} names no page")
                blocks += [(page, b) for b in e.get("blocks", [])]
            else:
                blocks.append((e["page"], e["block"]))
        rel = os.path.relpath(path, REPO)
        out.append(Writer(f"study {rel}", blocks, lambda check, p=path: study.regenerate(p, check, io.StringIO())))
    return out


# -- 2. commands ------------------------------------------------------------------------------


def command(name: str, args: List[str], blocks: List[Tuple[str, str]], check_args=("--check",)) -> Writer:
    from asg_analysis import commands

    def write(check: bool) -> int:
        return _quiet(lambda: commands.call(name, args + (list(check_args) if check else [])))[0]

    return Writer(f"{name} {' '.join(args)}".strip(), blocks, write)


# -- 3. tables read from the code ---------------------------------------------------------------


def _python_params() -> Dict[Tuple[str, str], object]:
    from asg_depth_stack.params import DEPTH_STACK
    from asg_lockstep.params import CLIENT, SCRIPTED_DRIVER
    from asg_perception.node_params import SEGMENTER

    return {
        ("docs/perception.md", "segmenter"): SEGMENTER,
        ("docs/your-stack.md", "depth_stack"): DEPTH_STACK,
        ("docs/your-stack.md", "lockstep_client"): CLIENT,
        ("docs/simulator.md", "scripted_driver"): SCRIPTED_DRIVER,
    }


# the C++ nodes and gap_nav's rospy node print their tables with --params: (page, node) -> (package, executable)
PRINTED = {
    ("docs/simulator.md", "scene_worker"): ("asg_sim", "scene_worker"),
    ("docs/your-stack.md", "wall_clock"): ("asg_sim", "wall_clock"),
    ("docs/your-stack.md", "twist_driver"): ("asg_lockstep", "twist_driver"),
    ("docs/your-stack.md", "gap_drive"): ("gap_nav", "gap_drive"),
}


def executable(package: str, name: str) -> str:
    """A package's executable by catkin's own search (the workspace's devel and install spaces,
    or the package's own nodes/ and scripts/ folders). FileNotFoundError naming it when there is none."""
    finder = shutil.which("catkin_find")
    if finder:
        r = subprocess.run([finder, "--first-only", package, name], capture_output=True, text=True)
        found = r.stdout.strip().splitlines()
        if r.returncode == 0 and found and os.access(found[0], os.X_OK):
            return found[0]
    for sub in ("nodes", "scripts"):
        path = os.path.join(REPO, "catkin_ws", "src", package, sub, name)
        if os.access(path, os.X_OK):
            return path
    raise FileNotFoundError(f"{package}/{name}: not built or not found (build the workspace, source its setup)")


def params_table(page: str, node: str) -> str:
    """The Markdown table of one node's parameters."""
    if (page, node) in PRINTED:
        path = executable(*PRINTED[(page, node)])
        return subprocess.run([path, "--params"], capture_output=True, text=True, check=True).stdout
    from asg_lockstep.params import markdown

    return markdown(_python_params()[(page, node)])


def package_deps(src: Optional[str] = None) -> Dict[str, List[str]]:
    """{package: the asg_* packages its package.xml depends on}, for every asg_* package."""
    src = src or os.path.join(REPO, "catkin_ws", "src")
    tags = ("depend", "exec_depend", "build_depend", "build_export_depend", "test_depend")
    out = {}
    for name in sorted(os.listdir(src)):
        xml = os.path.join(src, name, "package.xml")
        if name.startswith("asg_") and os.path.isfile(xml):
            root = ET.parse(xml).getroot()
            deps = {e.text.strip() for t in tags for e in root.iter(t) if e.text and e.text.strip().startswith("asg_")}
            out[root.findtext("name")] = sorted(deps)
    return out


def package_picture() -> str:
    deps = package_deps()
    width = max(len(n) for n in deps)
    rows = [f"{n:<{width}} -> {', '.join(d)}".rstrip() for n, d in deps.items()]
    return "```\n" + "\n".join(rows) + "\n```\n"


def generated_sources() -> Dict[str, str]:
    """{C++ file: the module that generates it}: every file whose first lines say
    "Generated by `python3 -m MODULE`"."""
    out = {}
    for root, _, files in os.walk(os.path.join(REPO, "catkin_ws", "src")):
        for f in sorted(files):
            if f.endswith((".hpp", ".h", ".cpp")):
                path = os.path.join(root, f)
                head = "".join(open(path, encoding="utf-8").readlines()[:4])
                m = re.search(r"Generated by `python3 -m ([\w.]+)`", head)
                if m:
                    out[os.path.relpath(path, REPO)] = m.group(1)
    return out


# what each generated C++ file holds, for the architecture page (a new generated file needs its line)
GENERATED_FROM = {
    "catkin_ws/src/asg_sim/include/asg_sim/scene_schema.hpp": (
        "the scenario schema (keys, each mapping's key list, units, ranges, defaults, terminations) and the "
        "obstacle catalogue (each class's size figures, the vehicle half width, the traversable height): "
        "asg_sim's validator, YAML reader, scene structs, mesh catalogue and dataset tool use it; a new "
        "obstacle class is a `catalogue.py` entry and its mesh function in `meshes.cpp` "
        "(tests/test_one_source.py compiles a made-up one)"
    ),
    "catkin_ws/src/asg_lockstep/include/asg_lockstep/client_params.hpp": (
        "the lockstep client's parameter table, one for its C++ and Python sides"
    ),
}


def pilot_choice() -> str:
    """The v3 pilot's scores in the order the record quotes them (results/flaw_study3/pilot_choice.json)."""
    with open(os.path.join(REPO, "results", "flaw_study3", "pilot_choice.json"), encoding="utf-8") as f:
        choice = json.load(f)
    return ", ".join(f"{k} {v:.1f}" for k, v in sorted(choice["searches"].items(), key=lambda kv: -kv[1]))


def mechanism_table() -> str:
    from asg_analysis.studies import mechanism

    with open(os.path.join(REPO, "results", "hardening", "mechanism", "mechanism.json"), encoding="utf-8") as f:
        return mechanism.markdown(json.load(f))


RECORD_LINE = re.compile(r"^\*Study record, (\d{4}-\d{2}-\d{2}) \((issues? #[^)]*)\)\. Status: ([^.]+)\.")


def records_index(root: Optional[str] = None) -> str:
    """docs/studies/README.md's table of the records, newest first (each record's line 3)."""
    root = root or os.path.join(REPO, "docs", "studies")
    rows = ["| recorded | record | issue | status |", "|---|---|---|---|"]
    for p in sorted(glob.glob(os.path.join(root, "????-??-??-*.md")), reverse=True):
        lines = open(p, encoding="utf-8").read().split("\n")
        rec = RECORD_LINE.match(lines[2] if len(lines) > 2 else "")
        if not rec:
            raise ValueError(f"{os.path.relpath(p, REPO)}: line 3 is not '*Study record, DATE (issue #N). Status: ...'")
        rows.append(f"| {rec.group(1)} | [{lines[0][2:]}]({os.path.basename(p)}) | {rec.group(2)} | {rec.group(3)} |")
    return "\n".join(rows)


def table(page: str, name: str, body: Callable[[], str], inline: bool = False) -> Writer:
    def write(check: bool) -> int:
        try:
            text = body()
        except (OSError, ValueError, subprocess.CalledProcessError) as e:
            print(f"{PROG}: {page} {name}: {e}", file=sys.stderr)
            return 2
        return rewrite_body(page, name, text, check, inline)

    return Writer(f"table {name}", [(page, name)], write)


def table_writers() -> List[Writer]:
    out = [
        table(p, f"params:{n}", lambda p=p, n=n: params_table(p, n)) for p, n in list(_python_params()) + list(PRINTED)
    ]

    def sources() -> str:
        gen = generated_sources()
        missing = sorted(set(gen) - set(GENERATED_FROM))
        if missing:
            raise ValueError(f"say what {', '.join(missing)} holds: asg_analysis/docs.py's GENERATED_FROM")
        rows = ["| generated file | generated by | from |", "|---|---|---|"]
        rows += [f"| `{f}` | `{gen[f]}` | {GENERATED_FROM[f]} |" for f in GENERATED_FROM if f in gen]
        return "\n".join(rows)

    out += [
        table("docs/architecture.md", "package dependencies", package_picture),
        table("docs/architecture.md", "generated sources", sources),
        table("docs/studies/README.md", "records", records_index),
        table("docs/design-loop.md", "mechanism", mechanism_table),
        table("docs/studies/2026-11-29-flaw-study-v3.md", "pilot choice", pilot_choice, inline=True),
    ]
    return out


# -- 4. and 5. the scripts of scripts/ci -----------------------------------------------------------


def ci_script(name: str):
    """scripts/ci/NAME.py as a module (its main(argv) runs in this process)."""
    path = os.path.join(REPO, "scripts", "ci", name + ".py")
    spec = importlib.util.spec_from_file_location(f"ci_{name}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def script(name: str, args: List[str], blocks: List[Tuple[str, str]]) -> Writer:
    def write(check: bool) -> int:
        return _quiet(lambda: ci_script(name).main(args + (["--check"] if check else [])))[0]

    return Writer(f"scripts/ci/{name}.py {' '.join(args)}", blocks, write)


REPEATS = ("r6-goalclient-repeat.txt", "r6-campaign-faults-repeat.txt", "r6-sound-runs-repeat.txt")


def writers() -> List[Writer]:
    """Every writer, in the order they run."""
    return (
        study_writers()
        + [
            command("coverage", ["doc"], [("docs/agent.md", "atlases"), ("README.md", "answer")]),
            command("defaults", [], [("docs/agent.md", "defaults")]),
            command("held-apart", ["--doc", "docs/design-loop.md"], [("docs/design-loop.md", "twins")]),
            command(
                "reliability",
                ["results/reliability/soak.json", "--doc", "docs/reliability.md"],
                [("docs/reliability.md", "soak")],
            ),
        ]
        + table_writers()
        + [
            script("readme_times", ["--doc", "README.md"], [("README.md", "times")]),
            script("readme_times", ["--doc", "docs/benchmarks.md"], [("docs/benchmarks.md", "avx2 train")]),
            script(
                "repeat_summary",
                [os.path.join("results", "flaky", r) for r in REPEATS] + ["--doc", "docs/testing.md"],
                [("docs/testing.md", "rostest repeat")],
            ),
            script("doc_figures", ["--doc", "docs/testing.md"], [("docs/testing.md", "doc figures")]),
        ]
    )


def unowned(all_writers: List[Writer], blocks: List[Tuple[str, str]], checked=None) -> Dict[str, List]:
    """What the pages and the writers disagree on: blocks with no writer (and not CHECKED), blocks
    with two, and blocks a writer names that no page holds."""
    owners: Dict[Tuple[str, str], List[str]] = {}
    for w in all_writers:
        for b in w.blocks:
            owners.setdefault(tuple(b), []).append(w.name)
    checked = CHECKED if checked is None else checked
    on_pages = set(blocks)
    return {
        "no writer": [b for b in blocks if b not in owners and b not in checked],
        "two writers": [(b, ws) for b, ws in owners.items() if len(ws) > 1],
        "not on its page": [b for b in list(owners) + list(checked) if b not in on_pages],
    }


def run(argv=None) -> int:
    p = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    p.add_argument("--check", action="store_true", help="exit 1 naming each stale block; write nothing")
    p.add_argument("--list", action="store_true", help="each block of the pages and what writes it")
    a = p.parse_args(argv)
    os.chdir(REPO)  # the writers take paths relative to the repository
    ws = writers()
    problems = unowned(ws, page_blocks())
    if a.list:
        for w in ws:
            for page, name in w.blocks:
                print(f"{page:<48} {name:<40} {w.name}")
        for (page, name), test in CHECKED.items():
            print(f"{page:<48} {name:<40} by hand, checked by {test}")
    bad = {k: v for k, v in problems.items() if v}
    for k, v in bad.items():
        print(f"{PROG}: {k}: {v}", file=sys.stderr)
    if a.list:
        return 1 if bad else 0
    from tqdm import tqdm

    stale, broken = [], []
    for w in tqdm(ws, desc="docs", unit="writer", disable=None, file=sys.stderr):
        rc, said = _quiet(lambda w=w: w.write(a.check))
        if rc == 1 and a.check:
            stale.append(w)
        elif rc != 0:
            broken.append((w, rc, said))
    for w in stale:
        print(f"stale: {w.name} ({', '.join(f'{pg} {n!r}' for pg, n in w.blocks)})")
    for w, rc, said in broken:
        print(f"{PROG}: {w.name} failed (exit {rc}): {said.strip()[-400:]}", file=sys.stderr)
    if not stale and not broken:
        print(f"{len(ws)} writers, {sum(len(w.blocks) for w in ws)} blocks: {'in step' if a.check else 'written'}")
    return 2 if broken or bad else (1 if stale else 0)
