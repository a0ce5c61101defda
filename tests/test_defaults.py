"""One set of campaign defaults (issues #94, #95): `rosrun asg_agent campaign`, launch/train.launch,
scripts/train.sh and docs/agent.md say the same defaults, those of asg_agent/defaults.py.

The launch file's defaults are read the way train.sh reads them, through roslaunch itself
(`roslaunch --args /campaign`: the campaign node's command line), then parsed by the CLI's own
parser, so what is compared is what each entry point runs."""

import os
import re
import shlex
import subprocess
import sys

import pytest

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(REPO, "catkin_ws", "src", "asg_agent", "src"))

from asg_agent import defaults  # noqa: E402
from asg_agent.cli import campaign as cli  # noqa: E402

LAUNCH = os.path.join(REPO, "launch", "train.launch")


def _settings(a) -> dict:
    """The table's settings of parsed CLI arguments, paths made comparable."""
    out = {}
    for name in defaults.DEFAULTS:
        v = getattr(a, name)
        if name in ("experiment", "store"):
            v = os.path.realpath(os.path.expanduser(v))
        out[name] = v
    return out


def _table() -> dict:
    out = {}
    for name, d in defaults.DEFAULTS.items():
        v = d.value
        if name == "experiment":
            v = os.path.realpath(os.path.join(REPO, v))
        elif name == "store":
            v = os.path.realpath(os.path.expanduser(v))
        elif name == "workers":
            v = str(v)
        out[name] = v
    return out


def test_the_cli_defaults_are_the_table():
    a = cli.parse([])
    got = _settings(a)
    want = _table()
    # reward auto is stored as what it stands for: with no references, the stack's own failures
    assert got.pop("reward") == "failure" and want.pop("reward") == "auto"
    assert got == want


def test_campaign_help_shows_each_default_of_the_table():
    out = subprocess.run(
        [sys.executable, "-m", "asg_agent.cli.campaign", "--help"], capture_output=True, text=True, check=True
    ).stdout
    flat = " ".join(out.split())
    for name in defaults.DEFAULTS:
        if name == "reward":  # its help explains auto at length
            assert "auto" in flat
            continue
        assert f"default {defaults.text(name)}" in flat.replace("exp1-route- wide", "exp1-route-wide"), name


@pytest.mark.skipif(subprocess.run(["which", "roslaunch"], capture_output=True).returncode, reason="needs ROS")
def test_train_launch_runs_the_campaign_with_the_tables_defaults():
    r = subprocess.run(["roslaunch", "--args", "/campaign", LAUNCH], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr[-2000:]
    words = shlex.split(r.stdout.strip().splitlines()[-1])
    # the node's own words (its interpreter and executable, whatever roslaunch prefixes) end where
    # the experiment file, its first argument, begins
    first = next(i for i, w in enumerate(words) if w.endswith(".yaml"))
    argv = [x for x in words[first:] if ":=" not in x]
    a = cli.parse(argv)
    assert a.method == defaults.DEFAULTS["method"].value
    launched = _settings(a)
    want = _table()
    # train.launch starts the three-stack references, so auto stands for the flaw reward there
    assert launched.pop("reward") == "flaw" and want.pop("reward") == "auto"
    assert "--reward auto" in " ".join(argv)
    assert launched == want


def test_train_sh_leaves_the_search_to_train_launch():
    text = open(os.path.join(REPO, "scripts", "train.sh"), encoding="utf-8").read()
    code = "\n".join(line for line in text.splitlines() if not line.lstrip().startswith("#"))
    for name in defaults.DEFAULTS:
        if name in ("scenarios", "store"):  # train.sh's own: 150 scenarios, results/train.sqlite
            continue
        assert f"{name}:=" not in code, name


def test_docs_say_the_defaults_of_the_table():
    from asg_analysis.docblocks import block_text

    doc = os.path.join(REPO, "docs", "agent.md")
    assert block_text(doc, "defaults").strip() == defaults.doc_table().strip(), "python3 -m asg_analysis defaults"
    # the option table's default column agrees with the table where it names one of its options
    rows = {}
    for line in open(doc, encoding="utf-8"):
        m = re.match(r"\| `(--[a-z-]+)` \| ([^|]*) \|", line)
        if m:
            rows[m.group(1)] = m.group(2).strip().strip("`")
    for name in defaults.DEFAULTS:
        opt = defaults.option(name)
        if opt in rows:
            assert rows[opt] in (defaults.text(name), "see Defaults"), (opt, rows[opt])
