#!/usr/bin/python3
"""rostest (issue #39): a stack written against standard messages only (asg_depth_stack) through
campaigns of the search, as docs/your-stack.md runs them: in lockstep, the stored runs replay bit
for bit; free-running, runs complete and are stored (not reproducible, so not compared)."""

import json
import os
import subprocess
import tempfile
import unittest

import rospy
import rostest

from asg_agent.campaign.store import Store, unpack_trajectory

import stack_util as su

SCENARIOS = 20  # lockstep campaign
FREE_SCENARIOS = 3  # free-running: real time, so few


def campaign(store, name, worker, scenarios, timeout):
    cmd = ["/usr/bin/python3", "-m", "asg_agent.cli.campaign", os.path.join(su.REPO, "experiments", "exp1-depth.yaml")]
    cmd += ["--method", "random", "--workers", worker, "--scenarios", str(scenarios), "--seed", "1"]
    cmd += ["--store", store, "--name", name, "--no-progress", "--no-tensorboard"]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)


class YourStack(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("your_stack_test")
        su.client("worker_0")
        su.client("worker_1")
        cls.dir = tempfile.mkdtemp()
        cls.store = os.path.join(cls.dir, "store.sqlite")

    def test_0_lockstep_campaign_stores_and_replays_bit_for_bit(self):
        p = campaign(self.store, "depth-lockstep", "worker_0", SCENARIOS, 800)
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
        # Two runs of a scenario: the stored one and its replay, identical to the last bit.
        for job in (rows[0]["job"], rows[-1]["job"]):
            p = subprocess.run(
                ["/usr/bin/python3", "-m", "asg_agent.ros.replay", self.store, "depth-lockstep", str(job)]
                + ["--worker", "/worker_0"],
                capture_output=True,
                text=True,
                timeout=300,
            )
            self.assertEqual(p.returncode, 0, p.stdout + p.stderr[-2000:])
            self.assertIn("REPRODUCED", p.stdout)
            self.assertIn("largest position difference to the stored run: 0.000000 m", p.stdout)

    def test_1_free_running_campaign_completes_and_is_stored(self):
        p = campaign(self.store, "depth-free", "worker_1", FREE_SCENARIOS, 600)
        self.assertEqual(p.returncode, 0, p.stdout[-2000:] + p.stderr[-2000:])
        rows = list(Store(self.store).rows("depth-free"))
        self.assertEqual(len(rows), FREE_SCENARIOS)
        for r in rows:
            self.assertNotEqual(r["termination"], "ERROR", r["error"])
            self.assertGreater(r["num_control_msgs"], 10)  # the stack drove: cmd_vel arrived


if __name__ == "__main__":
    rostest.rosrun("asg_tests", "your_stack", YourStack)
