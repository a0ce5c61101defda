"""The in-process stand-in for the worker pool, and the commands on it: test support, not part of
the running system. It lives beside the tests (catkin_ws/src/asg_agent/test/stand_in), is not
installed, and no module under a package's src/, nodes/ or scripts/ imports it
(test_stand_in_apart.py checks the rule).

    fake_pool      FakePool: a pool of stand-in workers (no ROS, no simulator)
    campaign       python3 -m stand_in.campaign EXPERIMENT --fake-workers N [campaign's options]
    suite          python3 -m stand_in.suite run SUITE --fake-workers N [suite run's options]
    asp_effect     python3 -m stand_in.asp_effect [--scenarios 1000] [--seeds 3] [--json] [--out]

A test of catkin_ws/src/asg_agent/test imports it as it imports its helpers beside it; a test of
another folder puts FOLDER first on sys.path, and a command runs with environ() (FOLDER first on
PYTHONPATH)."""

import os

#: catkin_ws/src/asg_agent/test: the folder that holds this package
FOLDER = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


#: catkin_ws/src/asg_agent/src: the agent's own sources, as this checkout holds them
SOURCES = os.path.join(os.path.dirname(FOLDER), "src")


def environ(base=None) -> dict:
    """`base` (default os.environ) with FOLDER and the agent's sources (SOURCES) first on
    PYTHONPATH: what `python3 -m stand_in.campaign` (or .suite, .asp_effect) needs to find this
    package and the agent code under test."""
    env = dict(os.environ if base is None else base)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (FOLDER, SOURCES, env.get("PYTHONPATH", "")) if p)
    return env
