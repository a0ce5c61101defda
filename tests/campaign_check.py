#!/usr/bin/python3
"""rostest (issue #10): `campaign` against two real workers fills the store, and a second
campaign with the same seed stores the same scenarios, proxies and trajectories."""
import os
import subprocess
import sys
import tempfile
import unittest

import rospy
import rostest

from asg_agent.store import Store, unpack_trajectory

import stack_util as su

SCENARIOS = 20


class CampaignEndToEnd(unittest.TestCase):
    def run_campaign(self, store, name):
        cmd = ["/usr/bin/python3", "-m", "asg_agent.cli", os.path.join(su.REPO, "experiments", "exp1.yaml"),
               "--workers", "2", "--scenarios", str(SCENARIOS), "--seed", "3", "--store", store, "--name", name,
               "--no-progress"]
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=500)
        self.assertEqual(p.returncode, 0, p.stdout[-2000:] + p.stderr[-2000:])
        return p.stdout

    def test_campaign_fills_the_store_and_repeats(self):
        rospy.init_node("campaign_test")
        su.client("worker_0")
        su.client("worker_1")
        path = os.path.join(tempfile.mkdtemp(), "store.sqlite")
        out = self.run_campaign(path, "first")
        self.assertIn("campaign first: 20 scenarios", out)
        self.run_campaign(path, "second")
        store = Store(path)
        a, b = store.content_digest("first"), store.content_digest("second")
        self.assertEqual(len(a), SCENARIOS)
        self.assertEqual([r[0] for r in a], list(range(SCENARIOS)))
        for ra, rb in zip(a, b):
            self.assertEqual(ra, rb, f"job {ra[0]} differs between the two campaigns")
        rows = list(store.rows("first"))
        self.assertEqual({r["worker"] for r in rows}, {"/worker_0", "/worker_1"})
        for r in rows:
            self.assertEqual(r["termination"] != "ERROR", r["proxy"] is not None)
            traj = unpack_trajectory(r["trajectory"])
            self.assertEqual(len(traj), r["samples"])
            self.assertGreater(r["samples"], 60)
        self.assertTrue(store.integrity_ok())


if __name__ == "__main__":
    rostest.rosrun("asg_tests", "campaign", CampaignEndToEnd)
