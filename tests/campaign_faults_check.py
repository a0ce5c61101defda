#!/usr/bin/python3
"""rostest (issue #14): a 40-scenario campaign while, in turn, worker_0's scene worker and
worker_1's planner are killed with SIGKILL mid-run, and then both planners hang (SIGSTOP) for
longer than three attempts take. Every scenario must be stored exactly once; the runs the deaths
cut short are re-queued and counted once (attempts 2); the scenario that met hung planners
everywhere is stored as ERROR after 3 attempts; the campaign goes on and finishes."""

import os
import signal
import subprocess
import tempfile
import time
import unittest

import rospy
import rostest

from asg_agent.records.store import Store

import stack_util as su

N = 40


class CampaignFaults(unittest.TestCase):
    def test_deaths_and_hangs(self):
        rospy.init_node("campaign_faults_test")
        su.client("worker_0")
        su.client("worker_1")
        tmp = tempfile.mkdtemp()
        exp = os.path.join(tmp, "exp1_gt.yaml")
        with open(exp, "w") as f:
            f.write(
                f"name: exp1gt\nscenario: {su.REPO}/scenarios/exp1.yaml\nperception: ground_truth\n"
                f"planner_config: planner.yaml\nepisode_steps: 5\nsim_timeout: 30.0\n"
            )
        path = os.path.join(tmp, "store.sqlite")
        p = subprocess.Popen(
            [
                "/usr/bin/python3",
                "-m",
                "asg_agent.cli.campaign",
                exp,
                "--workers",
                "2",
                "--method",
                "random",
                "--scenarios",
                str(N),
                "--store",
                path,
                "--name",
                "f",
                "--no-progress",
                "--answer-timeout",
                "120",
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        store = Store(path)

        def wait_stored(n, timeout=180):
            end = time.time() + timeout
            while time.time() < end and p.poll() is None:
                try:
                    if store.campaign("f") is not None and store.count("f") >= n:
                        return
                except Exception:  # noqa: BLE001 - the store is being created
                    pass
                time.sleep(0.05)
            self.fail(f"fewer than {n} scenarios stored in time")

        wait_stored(5)
        time.sleep(0.3)  # mid-run
        su.kill9("/worker_0/scene_worker")
        wait_stored(15)
        time.sleep(0.3)
        su.kill9("/worker_1/planner")
        wait_stored(25)
        planners = [su.node_pid("/worker_0/planner"), su.node_pid("/worker_1/planner")]
        for pid in planners:
            os.kill(pid, signal.SIGSTOP)
        time.sleep(20.0)  # 3 attempts x 3 s timeout, with the hand-overs and room for a loaded machine
        for pid in planners:
            os.kill(pid, signal.SIGCONT)
        out, err = p.communicate(timeout=400)
        self.assertEqual(p.returncode, 0, err[-3000:])
        rows = list(store.rows("f"))
        self.assertEqual(sorted(r["job"] for r in rows), list(range(N)), "a scenario lost or stored twice")
        self.assertTrue(store.integrity_ok())
        retried = [r for r in rows if r["attempts"] > 1]
        self.assertGreaterEqual(len(retried), 2, [(r["job"], r["attempts"], r["error"]) for r in rows if r["error"]])
        failed = [r for r in rows if r["termination"] == "ERROR"]
        self.assertGreaterEqual(len(failed), 1, "no scenario met the hung planners on every attempt")
        for r in failed:
            self.assertEqual(r["attempts"], 3)
            self.assertIn("planner", r["error"])
            self.assertIsNone(r["proxy"])
        self.assertIn("retrying elsewhere", err)


if __name__ == "__main__":
    rostest.rosrun("asg_tests", "campaign_faults", CampaignFaults)
