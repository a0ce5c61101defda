#!/usr/bin/python3
"""rostest (issue #39): a stack written against standard messages only (asg_depth_stack) through
campaigns of the search, as docs/your-stack.md runs them: in lockstep, the stored runs replay bit
for bit; free-running, runs complete and are stored (not reproducible, so not compared)."""

import json
import os
import re
import subprocess
import tempfile
import unittest

import rospy
import rostest

from asg_agent.records.store import Store, unpack_trajectory

import stack_util as su

SCENARIOS = 20  # lockstep campaign
FREE_SCENARIOS = 3  # free-running: real time, so few


DOC = os.path.join(su.REPO, "docs", "your-stack.md")


def doc_commands():
    """The shell commands of docs/your-stack.md's fenced bash blocks, continuation lines joined."""
    with open(DOC, encoding="utf-8") as f:
        blocks = re.findall(r"```bash\n(.*?)```", f.read(), re.S)
    return [" ".join(b.replace("\\\n", " ").split()) for b in blocks]


def doc_command(prefix, store, **swap):
    """The page's command that starts with `prefix`, as a list, run here: /usr/bin/python3, the
    store in the test's folder, and the other words of `swap` replaced."""
    (cmd,) = [c for c in doc_commands() if c.startswith(prefix)]
    words = {"python3": "/usr/bin/python3", "results/depth.sqlite": store, **swap}
    return [words.get(w, w) for w in cmd.split()]


def run(cmd, timeout):
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, cwd=su.REPO)


def campaign(store, timeout, **swap):
    return run(doc_command("python3 -m asg_agent.cli.campaign", store, **swap), timeout)


class YourStack(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("your_stack_test")
        su.client("worker_0")
        su.client("worker_1")
        cls.dir = tempfile.mkdtemp()
        cls.store = os.path.join(cls.dir, "store.sqlite")

    def test_0_lockstep_campaign_stores_and_replays_bit_for_bit(self):
        cmd = doc_command("python3 -m asg_agent.cli.campaign", self.store)
        self.assertEqual(cmd[cmd.index("--scenarios") + 1], str(SCENARIOS), "docs/your-stack.md's campaign size")
        self.assertEqual(cmd[cmd.index("--workers") + 1], "worker_0")
        p = run(cmd, 800)
        self.assertEqual(p.returncode, 0, p.stdout[-2000:] + p.stderr[-2000:])
        store = Store(self.store)
        settings = json.loads(store.campaign("depth-lockstep")["settings"])
        # Which stack and which interface: part of the stored identity.
        self.assertEqual((settings["stack"], settings["command_interface"]), ("depth", "twist"))
        rows = list(store.rows("depth-lockstep"))
        self.assertEqual(len(rows), SCENARIOS)
        for r in rows:
            self.assertNotEqual(r["termination"], "ERROR", r["error"])
            self.assertGreater(r["samples"], 60)
            self.assertEqual(len(unpack_trajectory(r["trajectory"])), r["samples"])
        # The depth stack drives: most of these random Exp. 1 layouts end at the goal.
        self.assertGreaterEqual(sum(r["termination"] == "SUCCESS" for r in rows), SCENARIOS // 2)
        # Step 5: the report, then two runs of a scenario (the stored one and its replay),
        # identical to the last bit.
        report = os.path.join(self.dir, "report")
        p = run(doc_command("python3 -m asg_analysis report", self.store, **{"results/depth-report": report}), 300)
        self.assertEqual(p.returncode, 0, p.stdout + p.stderr[-2000:])
        with open(os.path.join(report, "index.html"), encoding="utf-8") as f:
            page = f.read()
        self.assertIn("depth-lockstep", page)
        self.assertIn("stack: depth (command interface twist)", page)
        for job in (rows[0]["job"], rows[-1]["job"]):
            p = run(doc_command("python3 -m asg_agent.ros.replay", self.store, JOB=str(job)), 300)
            self.assertEqual(p.returncode, 0, p.stdout + p.stderr[-2000:])
            self.assertIn("REPRODUCED", p.stdout)
            self.assertIn("largest position difference to the stored run: 0.000000 m", p.stdout)

    def test_1_free_running_campaign_completes_and_is_stored(self):
        # The page's campaign command on the free-running worker (real time, so a few scenarios).
        swap = {"worker_0": "worker_1", "depth-lockstep": "depth-free", str(SCENARIOS): str(FREE_SCENARIOS)}
        p = campaign(self.store, 600, **swap)
        self.assertEqual(p.returncode, 0, p.stdout[-2000:] + p.stderr[-2000:])
        rows = list(Store(self.store).rows("depth-free"))
        self.assertEqual(len(rows), FREE_SCENARIOS)
        for r in rows:
            self.assertNotEqual(r["termination"], "ERROR", r["error"])
            self.assertGreater(r["num_control_msgs"], 10)  # the stack drove: cmd_vel arrived


if __name__ == "__main__":
    rostest.rosrun("asg_tests", "your_stack", YourStack)
