"""Issue #23: `baseline offline` runs planner variants on the baseline layouts without ROS, through
asg_planner_harness's asg_closed_loop and asg_agent's proxy. It is only worth its figures if, with the
default planner, it reproduces what the ROS ground-truth stack stored in results/baseline: the
same ending, simulated time and proxy on every layout it runs."""

import os
import subprocess
import sys

import pytest

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
for pkg in ("asg_agent", "asg_scenario"):
    sys.path.insert(0, os.path.join(REPO, "catkin_ws", "src", pkg, "src"))
from asg_agent.cli import baseline  # noqa: E402

EXP = os.path.join(REPO, "experiments", "exp1.yaml")
STORED = os.path.join(REPO, "results", "baseline", "exp1", "ground_truth.jsonl")
TOOL = os.path.join(REPO, "catkin_ws", "devel", "lib", "asg_planner_harness", "asg_closed_loop")
LAYOUTS = 6


def offline(root, *extra):
    # The suite runs after the build (scripts/test.sh): a missing tool is a failure, not a skip.
    assert os.access(TOOL, os.X_OK), f"{TOOL}: not built"
    return subprocess.run(
        [
            sys.executable,
            "-m",
            "asg_agent.cli.baseline",
            "offline",
            EXP,
            "--root",
            str(root),
            "--layouts",
            str(LAYOUTS),
            *extra,
        ],
        capture_output=True,
        text=True,
        env=dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path)),
        timeout=300,
    )


def test_offline_ground_truth_rows_equal_the_ros_stack_rows(tmp_path):
    res = offline(tmp_path, "--label", "default")
    assert res.returncode == 0, res.stderr
    rows = baseline.read_rows(str(tmp_path / "exp1" / "offline" / "default.jsonl"))
    stored = baseline.read_rows(STORED)
    assert sorted(rows) == list(range(LAYOUTS))
    for k in range(LAYOUTS):
        a, b = rows[k], stored[k]
        assert (a["termination"], a["collision_with"]) == (b["termination"], b["collision_with"]), k
        assert a["sim_time"] == pytest.approx(b["sim_time"], abs=1e-3), k
        # The tool writes trajectories to 5 decimals; the ROS result carries doubles.
        for key in ("proxy", "yaw_term", "plr", "vis"):
            assert a[key] == pytest.approx(b[key], abs=1e-4), (k, key)
    # Resumable: a second call finds every layout stored and runs none.
    again = offline(tmp_path, "--label", "default")
    assert again.returncode == 0 and f"{LAYOUTS} of {LAYOUTS} layouts stored" in again.stderr
    assert len(open(tmp_path / "exp1" / "offline" / "default.jsonl").read().splitlines()) == LAYOUTS


def test_offline_names_a_bad_planner_parameter(tmp_path):
    res = offline(tmp_path, "--label", "bad", "--set", "follower/kpp=3")
    assert res.returncode != 0
    assert "unknown planner parameter 'follower/kpp'" in res.stderr
    res = offline(tmp_path, "--label", "bad", "--set", "follower/kp")
    assert res.returncode == 2 and "expected KEY=VALUE" in res.stderr


def test_every_shipped_planner_yaml_loads_in_the_tool(tmp_path):
    # Issue #38: the tool read the planner table apart from the node and failed on the terrain keys
    # ("yaml-cpp: error at line 14, column 24: bad conversion"); every shipped YAML must load, and
    # with the default one the documented `baseline offline --planner` runs (the test above).
    assert os.access(TOOL, os.X_OK), f"{TOOL}: not built"
    config = os.path.join(REPO, "catkin_ws", "src", "asg_planner", "config")
    missing = str(tmp_path / "no_such_scenario.yaml")
    for name in sorted(os.listdir(config)):
        res = subprocess.run([TOOL, "--planner", os.path.join(config, name), missing], capture_output=True, text=True)
        # the planner file was read; only the scenario that is not there stops it
        assert res.returncode != 0 and f"{missing}: cannot read the file" in res.stderr, (name, res.stderr)
    res = offline(tmp_path, "--label", "paper", "--planner", os.path.join(config, "planner.yaml"))
    assert res.returncode == 0, res.stderr
    rows, stored = baseline.read_rows(str(tmp_path / "exp1" / "offline" / "paper.jsonl")), baseline.read_rows(STORED)
    for k in range(LAYOUTS):  # the node's parameters, read from the file: the ROS stack's runs
        assert rows[k]["termination"] == stored[k]["termination"], k
        assert rows[k]["proxy"] == pytest.approx(stored[k]["proxy"], abs=1e-4), k
