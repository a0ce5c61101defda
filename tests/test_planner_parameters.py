"""Issue #38: the planner's parameters have one home, the core's table (asg_planner/parameters.hpp).
The node and asg_closed_loop read it; docs/planner.md's table is its output; planner.yaml states its
defaults; every variant YAML is an overlay holding only what differs from planner.yaml."""

import os
import re
import subprocess

import yaml

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
TOOL = os.path.join(REPO, "catkin_ws", "devel", "lib", "asg_planner_harness", "asg_closed_loop")
NODE = os.path.join(REPO, "catkin_ws", "devel", "lib", "asg_planner", "planner")
CONFIG = os.path.join(REPO, "catkin_ws", "src", "asg_planner", "config")
DISPLAY = {"ack_name", "publish_markers"}  # the ROS adapter's own (docs/planner.md, below the table)


def table(tool=TOOL):
    assert os.access(tool, os.X_OK), f"{tool}: not built"
    res = subprocess.run([tool, "--params"], capture_output=True, text=True, check=True)
    return res.stdout


def flat(d, prefix=""):
    out = {}
    for k, v in d.items():
        out.update(flat(v, f"{prefix}{k}/") if isinstance(v, dict) else {f"{prefix}{k}": v})
    return out


def load(name):
    with open(os.path.join(CONFIG, name), encoding="utf-8") as f:
        return flat(yaml.safe_load(f))


def defaults():
    rows = [line.split("|") for line in table().splitlines()[2:]]
    return {r[1].strip().strip("`"): r[3].strip() for r in rows}


def test_the_docs_table_is_the_tables_output():
    with open(os.path.join(REPO, "docs", "planner.md"), encoding="utf-8") as f:
        docs = f.read()
    node = table(NODE)
    assert node.startswith(table()), "the node's table is the core's, then its adapter's rows"
    adapter = {line.split("|")[1].strip().strip("`") for line in node.splitlines()[2:]} - set(defaults())
    assert adapter == DISPLAY, "the adapter's own parameters are the ones the tools skip"
    assert node in docs, "docs/planner.md: paste the output of `planner --params` as its table"


def test_planner_yaml_states_every_default_of_the_table():
    base = {k: v for k, v in load("planner.yaml").items() if k not in DISPLAY}
    want = defaults()
    assert sorted(base) == sorted(want)
    for key, text in want.items():
        got = base[key]
        if isinstance(got, bool):
            assert str(got).lower() == text, key
        else:
            assert float(got) == float(text), (key, got, text)


def test_variants_are_overlays_of_what_differs():
    base = load("planner.yaml")
    variants = sorted(n for n in os.listdir(CONFIG) if re.fullmatch(r"planner_.+\.yaml", n))
    assert len(variants) == 4, variants
    for name in variants:
        over = load(name)
        assert over, name
        for key, v in over.items():
            assert key in base, f"{name}: {key} is not a planner parameter"
            assert v != base[key], f"{name}: {key} = {v!r} repeats planner.yaml"
