#!/usr/bin/python3
"""rostest (issue #14): a short run of the goal fuzzer against a real worker (the 1,000-goal run
is `fuzz_inputs.py goals`, docs/reliability.md): every goal ends, refusals name what is wrong,
the worker never restarts and its memory does not grow with the refused goals."""

import unittest

import rospy
import rostest

import stack_util as su
from fuzz_goals import fuzz_goals

GOALS = 150


class BadInput(unittest.TestCase):
    def test_fuzzed_goals(self):
        rospy.init_node("bad_input_test")
        su.client("worker_0")
        out = fuzz_goals(
            "/worker_0", GOALS, seed=3, pid_of=lambda: su.node_pid("/worker_0/scene_worker"), progress=False
        )
        rospy.loginfo("goal fuzz: %s", {k: v for k, v in out.items() if k != "failures"})
        self.assertEqual(out["failure_count"], 0, out["failures"][:5])
        self.assertGreaterEqual(len(out["classes"]), 10)
        self.assertGreater(out["outcomes"].get("ABORTED", 0), GOALS // 3)
        self.assertLess(out["rss_growth_kb_after_warmup"], 30 * 1024, out["rss_kb"])


if __name__ == "__main__":
    rostest.rosrun("asg_tests", "bad_input", BadInput)
